"""Running commands and API calls under a watchdog, and judging them against the contract.

The contract (the project's standards): a refused input ends the command with exit status 2
and exactly one short line on stderr (no traceback, no numpy warning); an answer exits 0
(successful) or 1 (answered, "not possible") and never marks valid what is not. Through the
API a refusal is an :class:`~assembler_pin.exceptions.AssemblerError` subclass; any other
exception is a defect. Nothing may run past its time limit.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import resource
import signal
import subprocess
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: Seconds a single command or call may take before it counts as a hang.
TIMEOUT = float(os.environ.get("ASSEMBLER_PIN_FUZZ_TIMEOUT", "60"))
#: Address-space limit of a child process [bytes]: an unbounded allocation fails there
#: instead of exhausting the machine.
CHILD_MEMORY = int(float(os.environ.get("ASSEMBLER_PIN_FUZZ_MEMORY_GB", "4")) * 2**30)
#: Longest acceptable one-line refusal [characters].
MAX_LINE = 1000
REPO = Path(__file__).resolve().parents[2]
WARNING_WORDS = ("RuntimeWarning", "UserWarning", "DeprecationWarning", "Warning:", "warnings.warn")


class Hang(BaseException):
    """Raised by the watchdog in the main thread (a BaseException: ``except Exception`` in
    the code under test cannot swallow it)."""


@dataclass
class Outcome:
    """What one command did: exit status, its streams, an escaped exception, a hang."""

    code: int | None
    out: str
    err: str
    exc: BaseException | None = None
    exc_text: str = ""
    hung: bool = False
    seconds: float = 0.0

    def summary(self) -> str:
        head = self.err.strip().splitlines()[-1][:300] if self.err.strip() else self.out.strip()[:200]
        return f"exit {self.code}: {head}"


@contextlib.contextmanager
def watchdog(seconds: float = TIMEOUT):
    """Raise :class:`Hang` in this (main) thread after ``seconds``."""

    def fire(signum, frame):
        raise Hang(f"no answer within {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, fire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@contextlib.contextmanager
def user_process_like(err: io.StringIO):
    """Warnings and logging as a user's process has them: Python's default warning filters
    (every RuntimeWarning shown) printed to the captured stderr, the root logger without
    handlers (``main`` installs its own on the captured stderr)."""
    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    np_state = np.geterr()
    with warnings.catch_warnings():
        warnings.resetwarnings()
        warnings.simplefilter("always")
        for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning):
            warnings.simplefilter("ignore", category)

        def show(message, category, filename, lineno, file=None, line=None):
            err.write(warnings.formatwarning(message, category, filename, lineno, line))

        warnings.showwarning = show
        root.handlers = []
        try:
            yield
        finally:
            root.handlers = handlers
            root.setLevel(level)
            np.seterr(**np_state)


def run_cli(argv: Sequence[str], cwd: Path | None = None, timeout: float = TIMEOUT) -> Outcome:
    """``assembler_pin.cli.main(argv)`` in this process: streams captured, stdin empty,
    a watchdog after ``timeout`` s. An exception escaping ``main`` is kept (a real process
    would print its traceback)."""
    from assembler_pin.cli import main

    out, err = io.StringIO(), io.StringIO()
    here = os.getcwd()
    t0 = time.perf_counter()
    result = Outcome(None, "", "")
    stdin = sys.stdin
    try:
        if cwd is not None:
            os.chdir(cwd)
        sys.stdin = io.StringIO("")
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), user_process_like(err):
            with watchdog(timeout):
                result.code = int(main(list(argv)))
    except Hang:
        result.hung = True
    except SystemExit as exc:
        result.code = exc.code if isinstance(exc.code, int) else 1
    except BaseException as exc:  # an escaped exception is what is judged
        result.exc = exc
        result.exc_text = "".join(traceback.format_exception_only(type(exc), exc)).strip()
    finally:
        sys.stdin = stdin
        os.chdir(here)
    result.out, result.err = out.getvalue(), err.getvalue()
    result.seconds = time.perf_counter() - t0
    return result


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (CHILD_MEMORY, CHILD_MEMORY))


def child_env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), *filter(None, [env.get("PYTHONPATH")])])
    env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", MPLBACKEND="Agg")
    env.pop("PYTHONWARNINGS", None)
    return env


def run_child(command: Sequence[str], cwd: Path | None = None, timeout: float = TIMEOUT, stdin: bytes = b"") -> Outcome:
    """A child process (its own session, memory-limited), killed with its group after
    ``timeout`` s."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        list(command),
        cwd=cwd,
        env=child_env(),
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
        preexec_fn=_limit_memory,
    )
    try:
        out, err = proc.communicate(stdin, timeout=timeout)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        return Outcome(
            None,
            out.decode(errors="replace"),
            err.decode(errors="replace"),
            hung=True,
            seconds=time.perf_counter() - t0,
        )
    finally:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGKILL)  # workers a command left behind
    return Outcome(
        proc.returncode, out.decode(errors="replace"), err.decode(errors="replace"), seconds=time.perf_counter() - t0
    )


def run_cli_child(argv: Sequence[str], cwd: Path | None = None, timeout: float = TIMEOUT) -> Outcome:
    """``python -m assembler_pin.cli ARGV`` as a child process (see :func:`run_child`)."""
    return run_child([sys.executable, "-m", "assembler_pin.cli", *argv], cwd, timeout)


# ---------------------------------------------------------------------- judging
class ContractError(AssertionError):
    """A broken contract; the message starts with its kind in brackets."""


def fail(kind: str, message: str) -> None:
    raise ContractError(f"[{kind}] {' '.join(message.split())[:600]}")


def judge_cli(o: Outcome, expect: str, what: str, timeout: float = TIMEOUT) -> None:
    """The outcome of one command against the contract.

    Args:
        expect: ``"refuse"`` (malformed input: must be exit 2), ``"answer"`` (valid input:
            must be answered) or ``"any"``.
        what: the command, for messages.
    """
    if o.hung:
        fail("hang", f"{what}: no answer within {timeout:g} s")
    if o.exc is not None:
        fail("traceback", f"{what}: {o.exc_text}")
    if "Traceback (most recent call last)" in o.err:
        last = o.err.strip().splitlines()[-1]
        fail("traceback", f"{what}: exit {o.code}: {last}")
    if o.code == 2:
        lines = o.err.strip("\n").splitlines()
        if len(lines) != 1:
            fail("noisy-refusal", f"{what}: {len(lines)} lines on stderr: {' | '.join(lines[:3])[:300]}")
        if any(w in o.err for w in WARNING_WORDS):
            fail("noisy-refusal", f"{what}: a warning beside the refusal: {o.err[:300]}")
        if len(lines[0]) > MAX_LINE:
            fail("noisy-refusal", f"{what}: a refusal line of {len(lines[0])} characters: {lines[0][:200]}")
        if expect == "answer":
            fail("valid-input-refused", f"{what}: {lines[0]}")
        return
    if o.code in (0, 1):
        if expect == "refuse":
            fail("accepted", f"{what}: exit {o.code} for a malformed input; stdout: {o.out.strip()[:200]}")
        if any(w in o.err for w in ("RuntimeWarning", "warnings.warn")):
            fail("noisy-refusal", f"{what}: a numpy warning on stderr beside the answer: {o.err[:300]}")
        return
    if o.code is not None and o.code < 0:
        fail("traceback", f"{what}: killed by signal {-o.code} ({o.err.strip()[-200:]})")
    fail("exit-status", f"{what}: exit status {o.code}: {o.err.strip()[-300:]}")


@dataclass
class Called:
    """What one API call did: its result, or the AssemblerError it raised."""

    result: object = None
    error: BaseException | None = None


def call_api(fn: Callable[[], object], expect: str, what: str, timeout: float = TIMEOUT) -> Called:
    """Call ``fn`` under the watchdog; judge what it raised against the contract.

    An :class:`AssemblerError` is a refusal (its message must be one short line); any other
    exception is ``[non-assembler-error]``; a return where ``expect == "refuse"`` is
    ``[accepted]``. Warnings are turned into errors (none may escape the library).
    """
    import assembler_pin as ap

    try:
        with watchdog(timeout), warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            result = fn()
    except Hang:
        fail("hang", f"{what}: no answer within {timeout:g} s")
    except ap.AssemblerError as exc:
        text = str(exc)
        if len(text) > MAX_LINE or "\n" in text.strip():
            fail("noisy-refusal", f"{what}: {type(exc).__name__} message of {len(text)} chars: {text[:200]}")
        if not text.strip():
            fail("noisy-refusal", f"{what}: {type(exc).__name__} without a message")
        if expect == "answer":
            fail("valid-input-refused", f"{what}: {type(exc).__name__}: {text}")
        return Called(error=exc)
    except RuntimeWarning as exc:
        fail("non-assembler-error", f"{what}: a numpy warning escaped: {exc}")
    except Exception as exc:  # any other exception: the defect judged here
        where = traceback.extract_tb(exc.__traceback__)[-1]
        fail(
            "non-assembler-error",
            f"{what}: {type(exc).__name__}: {str(exc)[:200]} (at {Path(where.filename).name}:{where.lineno})",
        )
    if expect == "refuse":
        fail("accepted", f"{what}: returned {type(result).__name__} {str(result)[:200]}")
    return Called(result=result)
