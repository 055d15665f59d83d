"""The statics: one equilibrium of a pose, and the backends that compute it.

- :mod:`.engine`: the statics of one pose (:func:`solve_statics`) and of a batch
  (:func:`solve_statics_batch`), on the compiled kernel.
- :mod:`.pinocchio_statics`: the reference from Pinocchio (per platform or whole-stack).
- :mod:`.result`: :class:`StaticsResult`.
- :mod:`.closed_form`: the equilibrium in closed form and the one condition number
  (:data:`CONDITION_LIMIT`).
- :mod:`.derivatives`: values and derivatives of the force objective with numpy (the
  optimizer's reference).
- :mod:`.kernel`, :mod:`.loops`: the compiled statics (numba); :mod:`.pose_kernel`,
  :mod:`.pose_loops`: compiled values and derivatives, the optimizer's engine.
- :mod:`.home`: the home pose on plain floats, for ``assembler-pin statics --home``.

The names below are imported on first use, so that ``statics --home`` (which imports
:mod:`.home`) loads no numpy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..common.lazy import lazy_attributes

#: public name -> the module of this package that defines it.
_LAZY: dict[str, str] = {
    "CONDITION_LIMIT": ".closed_form",
    "StaticsResult": ".result",
    "WHOLE_STACK_STATICS_MAX_PLATFORMS": ".pinocchio_statics",
    "checked_data": ".pinocchio_statics",
    "closure_jacobian_blocks": ".pinocchio_statics",
    "gravity_terms": ".pinocchio_statics",
    "solve_statics": ".engine",
    "solve_statics_batch": ".engine",
    "solve_statics_pinocchio": ".pinocchio_statics",
}

__all__ = [
    "CONDITION_LIMIT",
    "WHOLE_STACK_STATICS_MAX_PLATFORMS",
    "StaticsResult",
    "checked_data",
    "closure_jacobian_blocks",
    "gravity_terms",
    "solve_statics",
    "solve_statics_batch",
    "solve_statics_pinocchio",
]


__getattr__, __dir__ = lazy_attributes(__name__, globals(), _LAZY)

if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from .closed_form import CONDITION_LIMIT
    from .engine import solve_statics, solve_statics_batch
    from .pinocchio_statics import (
        WHOLE_STACK_STATICS_MAX_PLATFORMS,
        checked_data,
        closure_jacobian_blocks,
        gravity_terms,
        solve_statics_pinocchio,
    )
    from .result import StaticsResult
