"""The acquisition's continuous LP handed to HiGHS the way ``scipy.optimize.linprog(method="highs")`` hands it over,
without linprog's copy of the matrix.

With its dense path rows (a burn moves the along-track separation at every later epoch) the acquisition LP had
about 400,000 nonzeros and the solve was mostly HiGHS's presolve (about 0.12 s); their recursive form
(:func:`roe_sep.core.acquisition.planner._recursive_path`) leaves a few thousand. ``linprog`` adds about 0.05 s a
solve around the dense form: its wrapper copies the matrix into HiGHS's model element by element
(``HighsLp.a_matrix_.index_``/``value_`` are assigned from arrays through a list conversion) and builds per-column
marginals in a Python loop. :func:`solve_lp` passes the same model, arrays through the
buffer protocol (``Highs.passModel``), with the same options, to the same HiGHS (the one scipy ships), and so gets
the same solution to the bit (``test/core/acquisition/test_acquisition.py`` checks it against ``linprog`` on real
acquisition problems). Where that binding is not there (another scipy), it falls back to ``linprog`` itself.
"""

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # scipy.sparse is imported at the solve, not at import (the nodes import the planner's config)
    from scipy import sparse

#: HiGHS's presolve, on as in linprog (``bench/whatif_lp_presolve.py`` measures a campaign with it off)
PRESOLVE = "on"
#: HiGHS presolve rules switched off (its ``presolve_rule_off`` bit mask; 0: every rule on, as in linprog).
#: ``bench/whatif_lp_presolve.py --variant parallel-rows-off`` measures bit 13 (parallel rows and columns) off.
PRESOLVE_RULES_OFF = 0
#: linprog's scipy status codes and messages for HiGHS model statuses (scipy.optimize._linprog_highs)
_OPTIMAL, _INFEASIBLE = 0, 2
_MESSAGES = {_OPTIMAL: "Optimization terminated successfully. (HiGHS Status 7: Optimal)",
             _INFEASIBLE: "The problem is infeasible. (HiGHS Status 8: Infeasible)"}
# linprog's _check_result: a status-0 solution outside the constraints by more than sqrt(1e-9) * 10 is a failure
_CHECK_TOL = float(np.sqrt(1e-9) * 10)


class LPResult:
    """What the planner reads of a solve: ``status`` (linprog's codes: 0 optimal, 2 infeasible, 4 other failure),
    ``message``, ``x`` (None unless optimal), ``fun``, ``nit``."""

    __slots__ = ("status", "message", "x", "fun", "nit")

    def __init__(self, status, message, x=None, fun=None, nit=0):
        self.status, self.message, self.x, self.fun, self.nit = status, message, x, fun, nit


def _core():
    try:
        from scipy.optimize._highspy import _core as core
    except ImportError:  # another scipy layout: linprog itself
        return None
    return core if hasattr(core, "_Highs") and hasattr(core, "kHighsInf") else None


def _linprog(cost, a_ub, b_ub, a_eq, b_eq, *, lo, hi):
    from scipy.optimize import linprog

    res = linprog(cost, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=np.column_stack([lo, hi]),
                  method="highs")
    return LPResult(res.status, res.message, res.x if res.status == _OPTIMAL else None, res.fun, res.nit)


def solve_lp(cost: np.ndarray, a_ub: "sparse.spmatrix", b_ub: np.ndarray, a_eq: "sparse.spmatrix", b_eq: np.ndarray,
             *, lo: np.ndarray, hi: np.ndarray, use_linprog: bool = False) -> LPResult:
    """min cost @ x subject to a_ub x <= b_ub, a_eq x = b_eq, lo <= x <= hi (sparse a_ub, a_eq; linprog's form).

    The model is linprog's: rows ``vstack(a_ub, a_eq)`` in CSC, row bounds (-inf, b_ub) then (b_eq, b_eq), HiGHS's
    infinity for infinite bounds; the options are linprog(method="highs")'s (presolve on, dual simplex, no output).

    Parameters
    ----------
    cost : numpy.ndarray, shape (n,)
        The objective.
    a_ub, b_ub, a_eq, b_eq : scipy.sparse matrix, numpy.ndarray
        The inequality and equality rows ``(m, n)`` and their right-hand sides ``(m,)``.
    lo, hi : numpy.ndarray, shape (n,)
        The variable bounds (infinite allowed).
    use_linprog : bool
        Solve through ``linprog`` itself (tests compare the two).

    Returns
    -------
    LPResult
        Status, message, solution, objective and iterations.
    """
    core = None if use_linprog else _core()
    if core is None:
        return _linprog(cost, a_ub, b_ub, a_eq, b_eq, lo=lo, hi=hi)
    from scipy import sparse

    a = sparse.csc_array(sparse.vstack((a_ub, a_eq)))
    inf = core.kHighsInf
    row_lo = np.concatenate([np.full(len(b_ub), -inf), b_eq])
    row_hi = np.concatenate([b_ub, b_eq])
    col_lo, col_hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
    for v in (col_lo, col_hi, row_lo, row_hi):  # linprog's _replace_inf
        v[np.isinf(v)] = np.sign(v[np.isinf(v)]) * inf
    highs = core._Highs()
    for name, value in (("output_flag", False), ("log_to_console", False), ("presolve", PRESOLVE),
                        ("presolve_rule_off", PRESOLVE_RULES_OFF),
                        ("highs_debug_level", int(core.HighsDebugLevel.kHighsDebugLevelNone)),
                        ("simplex_strategy", int(core.simplex_constants.SimplexStrategy.kSimplexStrategyDual))):
        highs.setOptionValue(name, value)
    n_col, n_row = a.shape[1], a.shape[0]
    # HiGHS's array form: a column's start only (the end is the next start or nnz), every column continuous
    highs.passModel(n_col, n_row, a.nnz, int(core.MatrixFormat.kColwise), int(core.ObjSense.kMinimize), 0.0,
                    np.ascontiguousarray(cost, dtype=float), col_lo, col_hi, row_lo, row_hi,
                    a.indptr[:-1].astype(np.int32), a.indices.astype(np.int32), a.data.astype(float),
                    np.zeros(n_col, dtype=np.int32))
    highs.run()
    model = highs.getModelStatus()
    if model == core.HighsModelStatus.kInfeasible:
        return LPResult(_INFEASIBLE, _MESSAGES[_INFEASIBLE])
    if model != core.HighsModelStatus.kOptimal:
        return LPResult(4, f"HiGHS: {highs.modelStatusToString(model)}")
    solution, info = highs.getSolution(), highs.getInfo()
    x = np.array(solution.col_value)
    slack = row_hi - np.array(solution.row_value)
    con, slack = slack[len(b_ub):], slack[:len(b_ub)]
    if (np.any(x < col_lo - _CHECK_TOL) or np.any(x > col_hi + _CHECK_TOL) or np.any(slack < -_CHECK_TOL)
            or np.any(np.abs(con) > _CHECK_TOL) or not np.all(np.isfinite(x))):
        return LPResult(4, f"the solution does not satisfy the constraints within {_CHECK_TOL:.2E}")
    return LPResult(_OPTIMAL, _MESSAGES[_OPTIMAL], x, info.objective_function_value, info.simplex_iteration_count)
