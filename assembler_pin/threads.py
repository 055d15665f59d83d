"""One BLAS thread in the hot paths, so an answer is the same on every machine.

The optimizer's matrices are 24–190 wide: on them OpenBLAS's threads cost more than they
save (3–13× slower on a 2-core machine), and a threaded reduction sums in another order,
which moves SLSQP to a different optimum on some goals. Every entry point that runs the
optimizer or the helper arm (:func:`~assembler_pin.solver.solve`,
:func:`~assembler_pin.optimize.optimize_internal_poses`,
:func:`~assembler_pin.helper_arm.initial_condition`, motion planning, payload capacity, the
carrier's solve, map cells) runs under :func:`one_blas_thread`, whatever the caller's
thread setting; the caller's setting is restored on return.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, ParamSpec, TypeVar

__all__ = ["one_blas_thread", "single_blas_thread"]

P = ParamSpec("P")
R = TypeVar("R")

_controller: Any = None


def single_blas_thread() -> Any:
    """A context manager limiting every loaded BLAS (numpy's and scipy's) to one thread."""
    global _controller
    if _controller is None:
        import scipy.linalg  # noqa: F401  (load scipy's own OpenBLAS first, so it is limited too)
        from threadpoolctl import ThreadpoolController

        _controller = ThreadpoolController()
    return _controller.limit(limits=1, user_api="blas")


def one_blas_thread(func: Callable[P, R]) -> Callable[P, R]:
    """Decorator: run ``func`` under :func:`single_blas_thread`."""

    @functools.wraps(func)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        with single_blas_thread():
            return func(*args, **kwargs)

    return wrapper
