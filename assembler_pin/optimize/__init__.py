"""Force-optimized internal poses (paper §IV): choose the intermediate plate poses that
minimize the largest actuator force, subject to every physical constraint.

Decision variables: the poses of plates 1..n-1, each as a twist ``x_k`` in a fixed chart
around its starting pose, ``T_k = T_k⁰ · exp6(x_k)`` (local frame; plate 0 stays put).
Plate n sits at the goal; when the user allows an end-effector tolerance it becomes a
variable too, ``T_n = T_goal · exp6(x_n)``, with ``|x_n[3:]| <= rotation tolerance`` and
``|p_n - p_goal| <= position tolerance`` (:mod:`.charts`).

Objective (paper eq. 10): ``Ω = w1·max|F| + w2·sqrt(Σ λ_k²)``, with λ_k the angle between
``p_k - p_{k-1}`` and the rest direction of plate k on plate k-1 (eq. 9); written once, in
:mod:`assembler_pin.optimize.objective`.

Other objectives (``OptimizeOptions.objective``, slsqp only): ``"sag"`` minimizes the EE's
sag under its own load (legs stretched by F/k, :func:`~assembler_pin.compliance.loaded.sag_and_gradient`)
over the home pose's sag, every constraint kept (the force limits then are not capped by the
start's max|F|); ``"weighted"`` minimizes ``Ω + w·sag/sag_home``. ``max_sag`` adds the row
``sag <= max_sag`` (:class:`.rows.SagRows`). The sag's gradient is the exact adjoint one.

Methods:

* ``"slsqp"`` (default, :mod:`.smooth`): max|F| through an epigraph variable ``s``
  (``-s <= F_i <= s``), so the problem is smooth, and analytic gradients of every force,
  length, deflection and angle (:mod:`assembler_pin.statics.derivatives`) — scipy's SLSQP.
* ``"ipopt"`` (:mod:`.ipopt`, through CasADi): the same epigraph problem, rows and
  analytic derivatives, solved by IPOPT (through CasADi) on the constraint Jacobian's
  structural sparsity (platform j's legs move with plates j and j+1, its forces with plates
  j..n); every point IPOPT evaluates is tracked, so the best feasible one is never lost.
* ``"auto"``: IPOPT from :data:`~assembler_pin.config.options.AUTO_IPOPT_PLATFORMS` platforms up
  when CasADi is installed, SLSQP otherwise (the result's ``method`` names the one that ran).
* ``"paper"`` (:mod:`.paper`): the paper's literal formulation — the non-smooth ``max`` in
  the objective, the poses as TAA vectors in the world frame, gradients by scipy's finite
  differences — kept as the baseline to compare against.

Constraints (all methods, :mod:`.rows`): leg lengths, joint deflection (as cosines, smooth),
tension and compression limits (for ``slsqp`` also capped by the start's max|F|, so max|F|
never increases), continuous translation (every top joint at least ``rise_margin`` above its
bottom joint in the bottom plate's frame), end effector within tolerance.

Each iterate is evaluated by one closed-form pass (values, then derivatives from the same
pass where the solver asks for them, :mod:`.problem`); the returned state is evaluated again
with the Pinocchio statics, an independent path.

Along a motion (:mod:`assembler_pin.motion`) a :class:`MotionTerm` adds the paper's
"minimum required movement": ``w3·Σ (L_i - L_i^prev)²`` in the objective and, as
constraints, ``|L_i - L_i^prev| <= max_step`` for every leg (slsqp only).

The result never calls a constraint-violating state a success: the returned state is the
best *feasible* one met (checked again with the Pinocchio statics), the initial one when
nothing better was found, with the reason (:mod:`.result`).
"""

from __future__ import annotations

from ..config.options import METHODS, OptimizeOptions
from .internal_poses import optimize_internal_poses
from .objective import objective_value
from .options import MotionTerm
from .point import SINGULAR_FORCE
from .result import OptimizeResult

__all__ = [
    "METHODS",
    "SINGULAR_FORCE",
    "MotionTerm",
    "OptimizeOptions",
    "OptimizeResult",
    "objective_value",
    "optimize_internal_poses",
]
