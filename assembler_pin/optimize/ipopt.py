"""The interior-point method (``"ipopt"``): the smooth epigraph problem solved by IPOPT.

Same variables, rows, objective and analytic derivatives as :mod:`.smooth` (x = [poses in
the local chart, s]); IPOPT (through CasADi, the ``nlp`` extra) sees the constraint
Jacobian as a sparse matrix with its structural pattern (:func:`jacobian_pattern`):
platform j's legs move with plates j and j+1 only, its forces with plates j..n (the load
above it), so the pattern is banded for the leg rows and triangular for the force rows,
where SLSQP factors a dense matrix. The Hessian is IPOPT's limited-memory quasi-Newton one.

Every point IPOPT evaluates goes through :meth:`~.problem.Problem.point`, which keeps the
best feasible point met: the answer never loses a feasible point IPOPT visited.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..exceptions import OptionsError, _SingularIterateError
from ..options import IPOPT_INSTALL_HINT, casadi_missing
from ..threads import forget_loaded_libraries, single_blas_thread
from .problem import Problem
from .smooth import SmoothForm

__all__ = ["IpoptForm", "casadi_missing", "jacobian_pattern", "run_ipopt", "values_callback"]

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


def _platform_plates(problem: Problem) -> tuple[np.ndarray, np.ndarray]:
    """(legs, forces): (n, n+1) booleans, platform j (between plates j and j+1) depends on
    plate k through its legs (k in {j, j+1}) and through its forces (k >= j)."""
    n = problem.n
    k = np.arange(n + 1)[None, :]
    j = np.arange(n)[:, None]
    return (k == j) | (k == j + 1), k >= j


def jacobian_pattern(problem: Problem) -> np.ndarray:
    """(rows of :meth:`SmoothForm.cons`, nx) booleans: where the constraint Jacobian may be
    non-zero (a structural pattern, the same at every point).

    Rows in the order of :meth:`SmoothForm.cons`: ``s ∓ F`` (2·6n), the force limits (one
    row on ``s``, or 2·6n on the forces), the leg rows (5·6n), then the EE tolerance (2), the
    motion step (2·6n) and the sag limit (1, dense) where they apply.
    """
    chart, nx = problem.chart, problem.nx_pose + 1
    slot_of = np.full(problem.n + 1, -1)
    slot_of[chart.movable] = np.arange(len(chart.movable))
    # plate dependencies -> chart columns: (rows, n+1) @ (n+1, nx_pose)
    plate_cols = np.zeros((problem.n + 1, problem.nx_pose), dtype=bool)
    for k, slot in enumerate(slot_of):
        if slot >= 0:
            plate_cols[k, 6 * slot : 6 * slot + 6] = True
    legs, forces = _platform_plates(problem)

    def rows(platform: np.ndarray, copies: int, with_s: bool = False) -> np.ndarray:
        per_leg = np.repeat(platform, 6, axis=0)  # (6n, n+1), rows in forces.ravel() order
        cols = (per_leg.astype(int) @ plate_cols.astype(int)) > 0
        block = np.hstack([cols, np.full((cols.shape[0], 1), with_s)])
        return np.vstack([block] * copies)

    blocks = [rows(forces, 2, with_s=True)]
    if problem.force_limits.symmetric:
        s_only = np.zeros((1, nx), dtype=bool)
        s_only[0, -1] = True
        blocks.append(s_only)
    else:
        blocks.append(rows(forces, 2))
    blocks.append(rows(legs, 5))
    if problem.ee is not None:
        ee = np.zeros((2, nx), dtype=bool)
        ee[:, :-1] = plate_cols[problem.n]
        blocks.append(ee)
    if problem.motion_rows is not None:
        blocks.append(rows(legs, 2))
    if problem.sag_rows is not None:
        sag = np.ones((1, nx), dtype=bool)
        sag[0, -1] = False
        blocks.append(sag)
    return np.vstack(blocks)


class IpoptForm:
    """The epigraph problem of :class:`SmoothForm` with a sparse constraint Jacobian:
    the non-zeros of :meth:`SmoothForm.cons_jac` in compressed-column order."""

    def __init__(self, problem: Problem) -> None:
        self.problem = problem
        self.smooth = SmoothForm(problem)
        self.pattern = jacobian_pattern(problem)
        cols, rows = np.nonzero(self.pattern.T)  # column-major: CasADi's nonzero order
        self.rows, self.cols = rows, cols
        self.singular = ""
        self.interrupt: KeyboardInterrupt | None = None
        self._last: tuple[bytes, np.ndarray, np.ndarray] | None = None

    @property
    def shape(self) -> tuple[int, int]:
        """(constraint rows, variables)."""
        return self.pattern.shape

    def jacobian_nonzeros(self, x: np.ndarray) -> np.ndarray:
        """The pattern's entries of the constraint Jacobian at ``x``."""
        return self.smooth.cons_jac(x)[self.rows, self.cols]

    def derivatives(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(objective gradient (nx,), Jacobian non-zeros) at ``x``, computed once per point
        (IPOPT asks for both at the same point); NaN at a singular iterate, whose reason is
        kept in :attr:`singular`."""
        key = x.tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1], self._last[2]
        try:
            grad, nz = self.smooth.grad(x), self.jacobian_nonzeros(x)
        except _SingularIterateError as exc:
            self.singular = f"stopped at a singular iterate: {exc}"
            grad, nz = np.full(x.size, np.nan), np.full(self.rows.size, np.nan)
        self._last = (key, grad, nz)
        return grad, nz


def _guarded(form: IpoptForm, fill: Any) -> int:
    """Run ``fill()`` inside a CasADi callback: 0, or 1 after a Ctrl-C (kept in
    :attr:`IpoptForm.interrupt` and raised again once IPOPT returns: CasADi would take it
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


def _jacobian_callback(ca: Any, form: IpoptForm, g_sparsity: Any) -> Any:
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


def values_callback(form: IpoptForm) -> Any:
    """The CasADi callback x -> (objective, rows >= 0) of the form, whose Jacobian (the
    objective's gradient and the rows' sparse Jacobian, from the analytic derivatives) is
    a second callback on the structural pattern (:func:`_jacobian_callback`)."""
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
            return _guarded(form, lambda: _write(res, (lambda: form.smooth.fun(x), lambda: form.smooth.cons(x))))

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
#: ``sᵀy/sᵀs`` (``scalar1``, IPOPT's default). Measured on the bench's long stacks (iterations,
#: scalar1 → scalar2; the same optimum to 1e-10 relative): n = 4: 20 → 79, 12: 86 → 154,
#: 16: 123 → 75, 24: 81 → 71, 32: 186 → 65, 48: 100 → 58, 64: 122 → 58.
SCALAR2_PLATFORMS = 16


def ipopt_options(problem: Problem) -> dict:
    """IPOPT's settings from :class:`~assembler_pin.options.OptimizeOptions`.

    The iteration limit; ``tol = ftol``; and SLSQP's kind of stop on the objective: the
    "acceptable" level after 3 iterations whose objective changes by less than ``10·ftol``
    (relative) with the rows met to 1e-9 and complementarity 1e-6 (L-BFGS brings the dual
    infeasibility down slowly, the objective much sooner). The constraints are not relaxed
    (``bound_relax_factor = 0``); the Hessian is the limited-memory one, initialized by
    :data:`SCALAR2_PLATFORMS`; silent.
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
        "ipopt.mu_strategy": "adaptive",
        "ipopt.print_level": 0,
        "ipopt.sb": "yes",
        "print_time": False,
        "error_on_fail": False,
    }


def run_ipopt(problem: Problem, x0: np.ndarray) -> tuple[IpoptResult, str]:
    """Run IPOPT from ``x0`` (= [pose chart point, s]); returns (result, the reason when it
    stopped at a singular iterate else "")."""
    ca = _casadi()
    form = IpoptForm(problem)
    values = values_callback(form)
    X = ca.MX.sym("x", form.shape[1])
    f, g = values(X)
    solver = ca.nlpsol("assembler_ipopt", "ipopt", {"x": X, "f": f, "g": g}, ipopt_options(problem))
    with single_blas_thread():  # CasADi's OpenBLAS too (loaded after the caller's limit was set)
        sol = solver(x0=x0, lbg=0.0, ubg=np.inf)
    if form.interrupt is not None:
        raise form.interrupt
    stats = solver.stats()
    status = str(stats.get("return_status", "unknown"))
    x = np.asarray(sol["x"], dtype=float).ravel()
    success = status in _CONVERGED and not form.singular
    nit = int(stats.get("iter_count", 0))
    logger.debug("ipopt: %s after %d iterations", status, nit)
    return IpoptResult(x, f"IPOPT: {status}", success, 0 if success else -1, nit), form.singular
