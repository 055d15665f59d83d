"""The interior-point method (``"ipopt"``): the smooth epigraph problem solved by IPOPT.

The rows, objective and analytic derivatives of :mod:`.smooth`, in the moment-variable form
of :mod:`.wrench` (x = [poses in the local chart, the moments carried by each platform, s]):
IPOPT (through CasADi) sees a banded sparse constraint Jacobian, O(n)
non-zeros, where SLSQP factors a dense matrix. The Hessian is IPOPT's limited-memory
quasi-Newton one, its low-rank part in IPOPT's extended augmented system (one
factorization per iteration instead of a back-solve per stored pair).

Every point IPOPT evaluates goes through :meth:`~.problem.Problem.point`, which keeps the
best feasible point met: the answer never loses a feasible point IPOPT visited.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..common.threads import forget_loaded_libraries, single_blas_thread
from ..config.options import IPOPT_INSTALL_HINT, casadi_missing
from ..exceptions import OptionsError
from .problem import Problem
from .wrench import WrenchForm

__all__ = ["ipopt_options", "run_ipopt", "values_callback"]

logger = logging.getLogger(__name__)

#: IPOPT's return statuses that count as converged.
_CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


_plugin_loaded = False


def _casadi() -> Any:
    """The ``casadi`` module with its IPOPT plugin loaded, or an :class:`OptionsError` naming
    the extra to install."""
    global _plugin_loaded
    if casadi_missing():
        raise OptionsError(IPOPT_INSTALL_HINT)
    try:
        import casadi
    except ImportError:
        raise OptionsError(IPOPT_INSTALL_HINT) from None
    if not _plugin_loaded:
        casadi.load_nlpsol("ipopt")  # loads CasADi's own threaded OpenBLAS with it
        forget_loaded_libraries()  # so that single_blas_thread limits that one too
        _plugin_loaded = True
    return casadi


def _guarded(form: WrenchForm, fill: Any) -> int:
    """Run ``fill()`` inside a CasADi callback: 0, or 1 after a Ctrl-C (kept in
    :attr:`WrenchForm.interrupt` and raised again once IPOPT returns: CasADi would take it
    for a failed evaluation)."""
    if form.interrupt is not None:  # IPOPT's retries after a Ctrl-C: refused at once
        return 1
    try:
        fill()
    except KeyboardInterrupt as exc:
        form.interrupt = exc
        return 1
    return 0


def _write(res: list, values: tuple) -> None:
    """Copy each value (an array, or a function of nothing) into its output buffer; a
    ``None`` buffer is an output not asked for."""
    for out, value in zip(res, values, strict=True):
        if out is not None:
            np.frombuffer(out, dtype=np.float64)[:] = value() if callable(value) else value


def _jacobian_callback(ca: Any, form: WrenchForm, g_sparsity: Any) -> Any:
    """The callback (x, f, g) -> (objective gradient (1, nx), rows' Jacobian on the pattern)."""
    ng, nx = form.shape

    class Jacobian(ca.Callback):
        def __init__(self) -> None:
            ca.Callback.__init__(self)
            self.construct("assembler_jacobian", {"enable_fd": False})

        def get_n_in(self) -> int:
            return 3

        def get_n_out(self) -> int:
            return 2

        def get_sparsity_in(self, i: int) -> Any:
            return ca.Sparsity.dense(nx, 1) if i == 0 else ca.Sparsity(1, 1) if i == 1 else ca.Sparsity(ng, 1)

        def get_sparsity_out(self, i: int) -> Any:
            return ca.Sparsity.dense(1, nx) if i == 0 else g_sparsity

        def has_eval_buffer(self) -> bool:
            return True

        def eval_buffer(self, arg: list, res: list) -> int:
            x = np.frombuffer(arg[0], dtype=np.float64).copy()
            return _guarded(form, lambda: _write(res, form.derivatives(x)))

    return Jacobian()


def values_callback(form: WrenchForm) -> Any:
    """The CasADi callback x -> (objective, rows) of the form, whose Jacobian (the
    objective's gradient and the rows' sparse Jacobian, from the analytic derivatives) is
    a second callback on the form's structural pattern (:func:`_jacobian_callback`)."""
    ca: Any = _casadi()
    ng, nx = form.shape
    g_sparsity = ca.Sparsity.triplet(ng, nx, form.rows.tolist(), form.cols.tolist())

    class Values(ca.Callback):
        def __init__(self) -> None:
            ca.Callback.__init__(self)
            self.jacobians: list = []
            self.construct("assembler_values", {"enable_fd": False})

        def get_n_in(self) -> int:
            return 1

        def get_n_out(self) -> int:
            return 2

        def get_sparsity_in(self, i: int) -> Any:
            return ca.Sparsity.dense(nx, 1)

        def get_sparsity_out(self, i: int) -> Any:
            return ca.Sparsity.dense(1, 1) if i == 0 else ca.Sparsity.dense(ng, 1)

        def has_eval_buffer(self) -> bool:
            return True

        def eval_buffer(self, arg: list, res: list) -> int:
            x = np.frombuffer(arg[0], dtype=np.float64).copy()
            return _guarded(form, lambda: _write(res, (lambda: form.fun(x), lambda: form.cons(x))))

        def has_jac_sparsity(self, oind: int, iind: int) -> bool:
            return True

        def get_jac_sparsity(self, oind: int, iind: int, symmetric: bool) -> Any:
            return ca.Sparsity.dense(1, nx) if oind == 0 else g_sparsity

        def has_jacobian(self) -> bool:
            return True

        def get_jacobian(self, name: str, inames: list, onames: list, opts: dict) -> Any:
            jacobian = _jacobian_callback(ca, form, g_sparsity)
            self.jacobians.append(jacobian)  # CasADi holds no Python reference: keep every one
            return jacobian

    return Values()


@dataclass
class IpoptResult:
    """What is read of an IPOPT run (the fields of :class:`~.result.SolverResult`)."""

    x: np.ndarray
    message: str
    success: bool
    status: int
    nit: int


#: From this many platforms up, the limited-memory Hessian starts each update from the
#: least-squares scale of its first correction pair (IPOPT's ``scalar2``), below from
#: ``sᵀy/sᵀs`` (``scalar1``, IPOPT's default). Measured on the bench's long stacks
#: (iterations, scalar1 → scalar2, the same optimum to 1e-8 relative): n = 4: 21 → 101,
#: 8: 48 → 200 (the cap), 12: 105 → 200, 16: 116 → 72, 32: 101 → 84, 64: 105 → 64.
SCALAR2_PLATFORMS = 16


def ipopt_options(problem: Problem) -> dict:
    """IPOPT's settings from :class:`~assembler_pin.config.options.OptimizeOptions`.

    The iteration limit; ``tol = ftol``; and SLSQP's kind of stop on the objective: the
    "acceptable" level after 3 iterations whose objective changes by less than ``10·ftol``
    (relative) with the rows met to 1e-9 and complementarity 1e-6 (L-BFGS brings the dual
    infeasibility down slowly, the objective much sooner). The constraints are not relaxed
    (``bound_relax_factor = 0``); the Hessian is the limited-memory one, initialized by
    :data:`SCALAR2_PLATFORMS`, its low-rank part in the extended augmented system; silent.
    """
    opts = problem.opts
    return {
        "ipopt.limited_memory_initialization": "scalar2" if problem.n >= SCALAR2_PLATFORMS else "scalar1",
        "ipopt.max_iter": int(opts.max_iterations),
        "ipopt.tol": float(opts.ftol),
        "ipopt.acceptable_tol": 1e6,
        "ipopt.acceptable_iter": 3,
        "ipopt.acceptable_obj_change_tol": 10.0 * float(opts.ftol),
        "ipopt.acceptable_constr_viol_tol": 1e-9,
        "ipopt.acceptable_compl_inf_tol": 1e-6,
        "ipopt.constr_viol_tol": 1e-9,
        "ipopt.bound_relax_factor": 0.0,
        "ipopt.fast_step_computation": "yes",
        "ipopt.hessian_approximation": "limited-memory",
        "ipopt.limited_memory_aug_solver": "extended",
        "ipopt.mu_strategy": "adaptive",
        "ipopt.print_level": 0,
        "ipopt.sb": "yes",
        "print_time": False,
        "error_on_fail": False,
    }


def run_ipopt(problem: Problem, x0: np.ndarray) -> tuple[IpoptResult, str]:
    """Run IPOPT from ``x0`` (= [pose chart point, s], :meth:`.smooth.SmoothForm.x0`);
    returns (result, its ``x`` as [pose chart point, s]; the reason when it stopped at a
    singular iterate else "")."""
    ca = _casadi()
    form = WrenchForm(problem)
    values = values_callback(form)
    X = ca.MX.sym("x", form.shape[1])
    f, g = values(X)
    solver = ca.nlpsol("assembler_ipopt", "ipopt", {"x": X, "f": f, "g": g}, ipopt_options(problem))
    lbg, ubg = form.bounds
    with single_blas_thread():  # CasADi's OpenBLAS too (loaded after the caller's limit was set)
        sol = solver(x0=form.x0(x0), lbg=lbg, ubg=ubg)
    if form.interrupt is not None:
        raise form.interrupt
    stats = solver.stats()
    status = str(stats.get("return_status", "unknown"))
    x = form.smooth_x(np.asarray(sol["x"], dtype=float).ravel())
    success = status in _CONVERGED and not form.singular
    nit = int(stats.get("iter_count", 0))
    logger.debug("ipopt: %s after %d iterations", status, nit)
    return IpoptResult(x, f"IPOPT: {status}", success, 0 if success else -1, nit), form.singular
