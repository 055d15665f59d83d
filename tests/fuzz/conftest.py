"""Fixtures of the hostile-input harness, and the one place known failures are marked."""

from __future__ import annotations

import os

import pytest

from .known_failures import KNOWN

os.environ.setdefault("MPLBACKEND", "Agg")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "slow: takes more than a few seconds (deselect with -m 'not slow')")


def case_id(item: pytest.Item) -> str:
    """The id :data:`KNOWN` lists: the parameter id, or the test's function name."""
    callspec = getattr(item, "callspec", None)
    return callspec.id if callspec is not None else getattr(item, "originalname", item.name)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    here = os.path.dirname(__file__)
    for item in items:
        if str(item.fspath).startswith(here) and case_id(item) in KNOWN:
            item.add_marker(pytest.mark.xfail(strict=False, reason="known failure (tests/fuzz/known_failures.py)"))


@pytest.fixture(scope="session")
def ws(tmp_path_factory, am):
    """The workspace of hostile files (:func:`corpus.build_workspace`)."""
    import assembler_pin as ap

    from .corpus import NEAR_HOME, build_workspace

    root = tmp_path_factory.mktemp("fuzz")

    def plan() -> tuple[str, str]:
        goal = ap.kinematics.taa_to_se3([float(v) for v in NEAR_HOME.split()])
        motion = ap.plan_trajectory(am, ap.EEPath((am.home[-1], goal)), am.home)
        assert motion.trajectory is not None, motion.reason
        csv_path = motion.trajectory.write(root / "planned.csv")
        json_path = motion.trajectory.write(root / "planned.json")
        return csv_path.read_text(), json_path.read_text()

    return build_workspace(root, am, plan)


_REPORT = os.environ.get("ASSEMBLER_PIN_FUZZ_REPORT")
_RESULTS: dict[str, str] = {}


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    """With ``ASSEMBLER_PIN_FUZZ_REPORT=FILE``: every failing case's first message line,
    written to FILE as JSON {case id: message} at the end (the known-failures list's source)."""
    yield
    if _REPORT and call.when in ("setup", "call") and call.excinfo is not None:
        if call.excinfo.errisinstance((pytest.skip.Exception,)):
            return
        value = call.excinfo.value
        parts = list(getattr(value, "exceptions", None) or [value])  # a hypothesis ExceptionGroup: each
        lines = [(str(e).strip().splitlines() or [""])[0] for e in parts]
        _RESULTS[case_id(item)] = " || ".join(
            f"{type(e).__name__}: {line[:500]}" for e, line in zip(parts, lines, strict=True)
        )


def pytest_sessionfinish(session: pytest.Session) -> None:
    if _REPORT:
        import json

        with open(_REPORT, "w") as fh:
            json.dump(dict(sorted(_RESULTS.items())), fh, indent=1)
