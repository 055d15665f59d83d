"""One BLAS thread in the hot paths, so an answer is the same on every machine.

The optimizer's matrices are 24–190 wide: on them OpenBLAS's threads cost more than they
save (3–13× slower on a 2-core machine), and a threaded reduction sums in another order,
which moves SLSQP to a different optimum on some goals. Every entry point that runs the
optimizer or the helper arm (:func:`~assembler_pin.solver.pipeline.solve`,
:func:`~assembler_pin.optimize.optimize_internal_poses`,
:func:`~assembler_pin.helper_arm.initial_condition`, motion planning, payload capacity, the
carrier's solve, map cells) runs under :func:`one_blas_thread`, whatever the caller's
thread setting; the caller's setting is restored on return.

CasADi's IPOPT brings its own OpenBLAS (``libcasadi-tp-openblas``, threaded, loaded with the
solver plugin), which threadpoolctl does not know by name: it is registered here
(:class:`_CasadiOpenBLAS`), and :func:`forget_loaded_libraries` makes the next limit see a
library loaded after the first one was set.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, ParamSpec, TypeVar

__all__ = ["forget_loaded_libraries", "one_blas_thread", "single_blas_thread"]

P = ParamSpec("P")
R = TypeVar("R")

_controller: Any = None


def single_blas_thread() -> Any:
    """A context manager limiting every loaded BLAS (numpy's and scipy's) to one thread."""
    global _controller
    if _controller is None:
        import scipy.linalg  # noqa: F401  (load scipy's own OpenBLAS first, so it is limited too)
        from threadpoolctl import ThreadpoolController

        _register_casadi_openblas()
        _controller = ThreadpoolController()
    return _controller.limit(limits=1, user_api="blas")


def forget_loaded_libraries() -> None:
    """Make the next :func:`single_blas_thread` look again for the loaded BLAS libraries
    (call it after loading one, e.g. CasADi's IPOPT plugin; a search costs ~5 ms). CasADi's
    OpenBLAS is known to threadpoolctl from then on (``threadpool_info`` lists it too)."""
    global _controller
    _register_casadi_openblas()
    _controller = None


_registered = False


def _register_casadi_openblas() -> None:
    """Teach threadpoolctl CasADi's bundled OpenBLAS (once per process)."""
    global _registered
    if _registered:
        return
    import threadpoolctl

    class _CasadiOpenBLAS(threadpoolctl.OpenBLASController):
        """CasADi's own OpenBLAS (``libcasadi-tp-openblas.so``), used by its IPOPT and MUMPS."""

        filename_prefixes = ("libcasadi-tp-openblas",)

    threadpoolctl.register(_CasadiOpenBLAS)
    _registered = True


def one_blas_thread(func: Callable[P, R]) -> Callable[P, R]:
    """Decorator: run ``func`` under :func:`single_blas_thread`."""

    @functools.wraps(func)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        with single_blas_thread():
            return func(*args, **kwargs)

    return wrapper
