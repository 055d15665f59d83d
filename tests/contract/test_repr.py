"""Result objects print their key numbers in one readable line, never a numpy dump."""

from __future__ import annotations

import numpy as np

import assembler_pin as ap


def _readable(text: str, *numbers: str) -> None:
    assert len(text) < 400 and "\n" not in text and "array(" not in text, text
    for number in numbers:
        assert number in text, (number, text)


def test_reprs_carry_the_key_numbers(am):
    _readable(repr(am), "4 platforms", "24 legs", f"nv={am.model.nv}")
    state = ap.evaluate_state(am, am.home)
    peak = f"{float(np.abs(state.statics.forces).max()):.3f} N"  # recomputed from the forces
    _readable(repr(state), peak, "feasible")
    _readable(repr(state.statics), peak, f"{am.total_mass() * am.config.gravity:.3f}")
    _readable(repr(state.plates), "5 plates")
    fk = ap.stack_forward_kinematics(am, state.leg_lengths)
    _readable(repr(fk), "success=True", "converged")
    result = ap.solve(am, ap.scenario("orientation_transition").goal)
    _readable(
        repr(result), "success=True", f"{result.optimized.max_abs_force:.3f} N", f"{result.initial.max_abs_force:.3f} N"
    )
    _readable(repr(result.initial_result), f"{result.initial.max_abs_force:.3f} N")
    _readable(repr(result.optimization), f"{result.optimization.objective_optimized:.3f}")
    bad = ap.evaluate_state(am, am.home, goal=ap.scenario("translation").goal)
    _readable(repr(bad), "violations", "ee_position")
