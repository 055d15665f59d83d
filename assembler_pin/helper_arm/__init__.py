"""The helper arm: a fast, valid initial pose of the whole stack for a goal (paper §III).

The helper arm is a second, ordinary serial model (generated URDF, loaded into Pinocchio
with ``pin.buildModelFromXML``) that stands in for the stack:

* **Geometry.** A 3n-DOF arm: n *clusters* of three co-located revolute joints about
  the local x, y and z axes (in that order from the base, so a cluster rotates by
  ``Rx(a)·Ry(b)·Rz(c)``). The chain is::

      plate_0 (base) → d/2 → cluster 0 → d → cluster 1 → … → cluster n-1 → d/2 → plate_n (tip)

  with every link along the local +z axis. Cluster j (URDF joints ``sp{j}_rx``,
  ``sp{j}_ry``, ``sp{j}_rz``; the paper's cluster j+1) sits at the mid-height point of
  Stewart platform j. The fixed links ``plate_k`` (k = 1..n-1) are the midpoints of the
  links between clusters k-1 and k, with that link's orientation — "the plates at the
  midpoints between the arm joints" of the paper. So SP j's relative pose is
  ``T(d/2) · R_cluster_j · T(d/2)``: a tilt/twist of the top plate about the platform's
  mid-height point, which is the motion that spreads the stroke most evenly over the
  six legs. ``plate_n``, the tip, is the end effector. ``d`` starts at the home SP
  height ``d0 = cfg.home_height`` (at ``q = 0`` the arm *is* the home pose).

* **Joint limits** come from what one SP can do about its mid-height point at height
  ``d`` (:func:`cluster_limits`): the x and y joints get the largest tilt ``θ`` such
  that ``T(d/2)·exp3(θ·a)·T(d/2)`` keeps every leg of every platform within
  ``[min_length, max_length]``, both joint deflections ``<= max_deflection`` and the
  top joints above the bottom joints — the minimum over 24 horizontal axes ``a``
  (every 15°), found by bisection to 1e-10 rad. The z joint gets the same for a twist
  about z (minimum of both signs). A box of such limits does not guarantee a valid
  stack (a tilt about x and y at once is larger than either), so every arm solution is
  checked on the real stack afterwards.

* **IK** (:meth:`HelperArm.ik`): ``scipy.optimize.least_squares`` (``trf``, bounds = the
  joint limits) on the 6D error ``log6(goal⁻¹ · tip(q))`` with its analytic Jacobian
  ``Jlog6 · J_tip`` (Pinocchio LOCAL frame Jacobian), plus two more residual blocks:
  the stack's own leg constraints (stroke, deflection, continuous translation) of the
  plates the arm would place, as a hinge penalty (:meth:`HelperArm.stack_violation`,
  forward-difference Jacobian) — the box limits alone let combined x/y tilts break
  legs — and a pull ``w·q`` toward zero so that the bending is spread evenly over the
  clusters (the paper's "minimize angular deviation"). A second solve without the pull
  (up to 100 evaluations) then drives the goal error to machine precision.
  **The link length d is a variable of the same solve** (``link_range``, bounded to
  :func:`height_range`; not pulled): every translation of the arm is ``d`` times one of
  the unit arm, so the tip moves by ``R_tipᵀ·p_tip/d`` (LOCAL) per unit of d and the
  model built for one d serves all. This removes the singularity of a straight arm,
  which cannot change its length by bending, and the need for the scan to hit the right
  d exactly (a straight-up goal at z is solved with d = z/n, q = 0). Optional
  deterministic restarts (``HelperArmOptions.restarts``, default none: they did not
  raise the success rate, nor did a start bent toward the goal).

* **Initial condition** (:func:`initial_condition`): the paper's recursive scan over d,
  each scan value being the *start* of d in the IK above: first ``d0`` (the paper's
  start), then ``d* = |p_goal - p_base| / n`` (the straight arm's length to the goal,
  clipped half a step inside :func:`height_range`) and ``d* + s, d* - s, d* + 2s, …``
  (``s`` the user step; values within s/2 of d0 are left out), until ``max_attempts``
  arm solves (the paper's recursion limit), skipping heights where a level SP cannot
  tilt or twist. When the arm reaches the goal with valid plates, plate n is put exactly
  at the goal and the leg lengths follow from the SP IK
  (:func:`~assembler_pin.kinematics.leg_state`), and every kinematic constraint of the
  stack is checked. When no scan value works (the arm model only tilts each SP about its
  mid-height point at one common height; it cannot shear an SP sideways, which low goals
  need), a **repair** on the stack itself follows: from the ``repair_starts`` (default 2)
  arm poses closest to valid (goal error + leg violation), then from the "even screw"
  pose (plate k at ``base·exp6(k/n · log6(base⁻¹·goal))``), plates 1..n-1 are moved
  (``least_squares`` on the legs' constraint violations, 1e-6 inside every bound, plates
  0 and n fixed) until every leg is valid, and the result is checked as above
  (``InitialConditionResult.repaired``). On failure the home pose is returned with
  ``success=False`` and the reason. Unreachable goals are answers, never exceptions;
  malformed goals raise :class:`~assembler_pin.exceptions.PoseError`.

Frames: the arm's base is plate 0's world pose (``am.home[0]``, identity by default);
all poses returned are world poses. Units: metres and radians.

Modules: :mod:`.limits` (what one platform can do), :mod:`.urdf` (the arm's URDF),
:mod:`.arm` (model, FK, IK problem), :mod:`.cache` (the arms by link length, owned by
the caller: ``initial_condition(..., arms=ArmCache(cfg))``, or by default one per thread
and configuration), :mod:`.repair` (the stack repair),
:mod:`.options`, :mod:`.link_lengths` (the order of the d scan) and :mod:`.initial` (the d scan
and its result). Measured success rates
are in the README.
"""

from ..config.options import HelperArmOptions
from ..kinematics.legs import relative_leg_measures
from .arm import ArmIKProblem, ArmIKResult, HelperArm
from .cache import ArmCache, arm_cache
from .initial import KINEMATIC_VIOLATIONS, initial_condition
from .limits import cluster_limits, height_range
from .outcome import Candidate, InitialConditionResult
from .repair import perturbed_plates, repair_stack
from .urdf import HELPER_ARM_URDF_FILENAME, helper_arm_urdf

__all__ = [
    "HELPER_ARM_URDF_FILENAME",
    "KINEMATIC_VIOLATIONS",
    "ArmCache",
    "ArmIKProblem",
    "ArmIKResult",
    "Candidate",
    "HelperArm",
    "HelperArmOptions",
    "InitialConditionResult",
    "arm_cache",
    "cluster_limits",
    "height_range",
    "helper_arm_urdf",
    "initial_condition",
    "perturbed_plates",
    "relative_leg_measures",
    "repair_stack",
]
