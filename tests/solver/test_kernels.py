"""One answer on every machine: the same goals solved under other OpenBLAS kernels.

OpenBLAS picks its kernel by the CPU (``OPENBLAS_CORETYPE`` forces one); kernels round
differently, and a decision taken on a solver's status code or on an exact comparison of
floats can then flip. Each kernel this CPU runs solves a fixed goal set in its own process;
every verdict (valid, optimal, the reason when not) must be the same and every optimum within
0.1 % of the others.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import pytest

#: Why the tests marked with it fail today (known, open).
OWN_PLATE_RULE = (
    "the check of each leg against its own plates refuses the leaning poses these goals were answered "
    "with (a motor inside a plate); the optimizer does not yet find a clear pose for all of them"
)


#: The kernels compared and the CPU flag each needs.
KERNELS = {"Sandybridge": "avx", "Haswell": "avx2", "SkylakeX": "avx512f"}

#: Low goals that only a leaning stack reaches (the lean starts and their restarts), low goals
#: with a compressed optimum whose best local optimum a start found on some kernels only,
#: goals on a seeded random set of reachable poses, and one out of reach near the base plane.
SOLVE_GOALS = """
import json, sys
import numpy as np, pinocchio as pin
import assembler_pin as ap
from assembler_pin.kinematics import stack_forward_kinematics

am = ap.AssemblerModel.from_config()
low = ([0.2, 0.2, 0.5], [-0.2, 0.2, 0.5], [-0.3, 0.2, 0.5], [0.3, -0.2, 0.5], [0.5, 0.5, 0.0])
goals = [pin.SE3(np.eye(3), np.array(p)) for p in low]
rng = np.random.default_rng(2026)
while len(goals) < 11:
    lengths = rng.uniform(am.config.leg.min_length + 0.01, am.config.leg.max_length - 0.01, (am.n, 6))
    fk = stack_forward_kinematics(am, lengths)
    if fk.success:
        goals.append(fk.plates.se3(am.n))
out = []
for goal in goals:
    r = ap.solve(am, goal)
    out.append({"success": r.success, "optimal": r.optimal,
                "max_abs_force": r.best.max_abs_force if r.success else None,
                "cause": r.message.split(":")[0] if not r.success else ""})
json.dump(out, sys.stdout)
"""


def _cpu_flags() -> set[str]:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    for line in text.splitlines():
        if line.startswith("flags"):
            return set(line.split(":", 1)[1].split())
    return set()


def _kernels_here() -> list[str]:
    if platform.machine() not in ("x86_64", "AMD64"):
        return []
    flags = _cpu_flags()
    return [kernel for kernel, flag in KERNELS.items() if flag in flags]


def _solved_under(kernel: str) -> list[dict]:
    env = {**os.environ, "OPENBLAS_CORETYPE": kernel, "OMP_NUM_THREADS": "1"}
    done = subprocess.run(
        [sys.executable, "-c", SOLVE_GOALS], env=env, capture_output=True, text=True, timeout=600, check=False
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout)


@pytest.mark.xfail(reason=OWN_PLATE_RULE, strict=False)
def test_verdicts_and_optima_are_the_same_under_every_kernel():
    kernels = _kernels_here()
    if len(kernels) < 2:
        pytest.skip("this CPU runs fewer than two OpenBLAS x86-64 kernels")
    answers = {kernel: _solved_under(kernel) for kernel in kernels}
    first, *others = kernels
    reference = answers[first]
    assert sum(a["success"] for a in reference) >= 10  # the set holds answers to compare
    for kernel in others:
        for k, (a, b) in enumerate(zip(reference, answers[kernel], strict=True)):
            where = f"goal {k}: {first} {a} vs {kernel} {b}"
            assert (a["success"], a["optimal"], a["cause"]) == (b["success"], b["optimal"], b["cause"]), where
            if a["success"]:
                assert b["max_abs_force"] == pytest.approx(a["max_abs_force"], rel=1e-3), where
