"""The acquisition LP's named blocks (:mod:`roe_sep.core.acquisition.planner`): each block's rows, columns and
bounds checked against a small hand-computed problem (two candidate columns on two grid epochs), and the assembled
program equal to the blocks stacked in their documented order."""

import dataclasses
import math

import numpy as np
import pytest

from roe_sep.core.acquisition import planner as P

TOL = 1.0
# two candidates (epoch 0 axis T, epoch 1 axis T); final a*ROE per quantum of each: rows da, dl, dex, dey, dix, diy
FINAL = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0], [7.0, 8.0], [9.0, 10.0], [11.0, 12.0]])
FREE = np.array([0.5, 100.0, 10.0, 20.0, 30.0, 40.0])
IHAT = np.array([1.0, 0.0])  # so j^ = (0, 1)
COLS = np.array([0, 1])


def problem(s=-1.0, barred=(False, False), radial=False, **cfg):
    config = P.AcquisitionConfig(**{"drift_tolerance": TOL, "fov_half_r_deg": 45.0, "fov_half_n_deg": 45.0, **cfg})
    path = np.array([[0.0, 0.0], [2.0, 0.0]])  # s a dl per quantum at grid epochs 0, 1 (post-burn)
    return P._Problem(
        cfg=config, epochs=np.array([0.0, 100.0]), axes=(1,), final=FINAL, free_final=FREE, path=path,
        path_pre=np.array([[0.0, 0.0], [0.0, 0.0]]) if radial else None, free_path=np.array([6000.0, 5500.0]),
        path_floor=5010.0, epoch_of=np.array([0, 1]), barred=np.array(barred), s=s, quanta_max=300, ei_floor=160.0)


def test_the_layout_names_the_columns():
    lay = P._Layout(2)
    assert (lay.size, lay.l, lay.mu, lay.nu) == (7, 4, 5, 6)
    np.testing.assert_array_equal(lay.row([1.0, 2.0, 3.0, 4.0], {lay.mu: 9.0}), [1, 2, 3, 4, 0, 9, 0])


def test_the_objective_is_the_l1_delta_v_in_quanta():
    np.testing.assert_array_equal(P._objective(P._Layout(2)), [1, 1, 1, 1, 0, 0, 0])


def test_the_drift_row_bounds_a_da_f():
    dmat = np.hstack([FINAL, -FINAL])
    rows = P._drift_rows(P._Layout(2), dmat, FREE, TOL)
    np.testing.assert_array_equal(rows.a, [[1, 2, -1, -2, 0, 0, 0]])
    np.testing.assert_array_equal((rows.lb, rows.ub), ([-1.5], [0.5]))  # -1 <= 0.5 + da(v) <= 1


def test_the_along_track_row_defines_l():
    dmat = np.hstack([FINAL, -FINAL])
    rows = P._along_track_rows(P._Layout(2), dmat, FREE, -1.0)
    np.testing.assert_array_equal(rows.a, [[3, 4, -3, -4, 1, 0, 0]])  # 100 + dl(v) = s L = -L
    np.testing.assert_array_equal((rows.lb, rows.ub), ([-100.0], [-100.0]))


def test_the_exact_ei_rows_align_e_and_i_with_ihat():
    dmat = np.hstack([FINAL, -FINAL])
    rows = P._ei_direction_rows(P._Layout(2), dmat, FREE, IHAT, s=-1.0, exact=True, tg=0.1)
    np.testing.assert_array_equal(rows.a, [[5, 6, -5, -6, 0, -1, 0],  # dex_F = -s mu = mu
                                           [9, 10, -9, -10, 0, 0, -1],  # dix_F = nu
                                           [7, 8, -7, -8, 0, 0, 0]])  # dey_F = 0
    np.testing.assert_array_equal(rows.lb, [-10.0, -30.0, -20.0])
    np.testing.assert_array_equal(rows.ub, rows.lb)


def test_the_quantized_ei_rows_are_tolerance_cones():
    dmat = np.hstack([FINAL, -FINAL])
    rows = P._ei_direction_rows(P._Layout(2), dmat, FREE, IHAT, s=1.0, exact=False, tg=0.1)
    np.testing.assert_array_equal(rows.a, [[5, 6, -5, -6, 0, 1, 0],  # dex_F = -mu (leading)
                                           [9, 10, -9, -10, 0, 0, -1],
                                           [7, 8, -7, -8, 0, -0.1, 0],  # |dey_F| <= 0.1 mu
                                           [-7, -8, 7, 8, 0, -0.1, 0],
                                           [11, 12, -11, -12, 0, 0, -0.1],  # |diy_F| <= 0.1 nu
                                           [-11, -12, 11, 12, 0, 0, -0.1]])
    np.testing.assert_array_equal(rows.lb, [-10.0, -30.0] + [-np.inf] * 4)
    np.testing.assert_array_equal(rows.ub, [-10.0, -30.0, -20.0, 20.0, -40.0, 40.0])


def test_the_fov_rows_follow_eq_11():
    rows = P._fov_rows(P._Layout(2), problem().cfg, 0.5)
    t = math.tan(math.radians(45.0))
    np.testing.assert_array_equal(rows.a, [[0, 0, 0, 0, -t, 2, 0], [0, 0, 0, 0, -t, 0, 2]])
    np.testing.assert_array_equal((rows.lb, rows.ub), ([-np.inf] * 2, [0.0, 0.0]))


@pytest.mark.parametrize("radial", [False, True])
def test_the_path_rows_keep_the_separation(radial):
    blocks, lb = P._path_rows(problem(radial=radial), COLS)
    assert len(blocks) == (2 if radial else 1)
    np.testing.assert_array_equal(blocks[0].toarray(), [[0, 0, 0, 0, 0, 0, 0], [2, 0, -2, 0, 0, 0, 0]])
    assert lb == [-990.0, -490.0] * len(blocks)  # floor 5010 - free 6000, 5010 - 5500


def test_the_burn_magnitude_rows_group_by_epoch():
    pb = problem()
    pb.epoch_of[:] = [3, 3]  # both candidates on one epoch: one row
    block, ub = P._burn_magnitude_rows(pb, COLS)
    np.testing.assert_array_equal(block.toarray(), [[1, 1, 1, 1, 0, 0, 0]])
    assert ub == [300]
    block, ub = P._burn_magnitude_rows(problem(), COLS)
    np.testing.assert_array_equal(block.toarray(), [[1, 0, 1, 0, 0, 0, 0], [0, 1, 0, 1, 0, 0, 0]])
    assert ub == [300, 300]


def test_the_variable_bounds():
    lay = P._Layout(2)
    lo, hi = P._variable_bounds(problem(barred=(False, True)), lay, COLS, exact=True, target=True, ei=True)
    np.testing.assert_array_equal(lo, [0, 0, 0, 0, 7500, 160, 160])
    np.testing.assert_array_equal(hi, [300, 0, 300, 0, 7500, np.inf, np.inf])  # epoch 1 barred
    lo, hi = P._variable_bounds(problem(), lay, COLS, exact=False, target=True, ei=False)
    np.testing.assert_array_equal(lo, [0, 0, 0, 0, 7300, 0, 0])
    np.testing.assert_array_equal(hi, [300, 300, 300, 300, 7700, 0, 0])
    lo, hi = P._variable_bounds(problem(), lay, COLS, exact=True, target=False, ei=True)
    assert (lo[4], hi[4]) == (5000.0, 10000.0)


@pytest.mark.parametrize("exact", [True, False])
@pytest.mark.parametrize("flags", [{}, {"path": False}, {"ei": False}])
def test_the_program_stacks_the_blocks_in_order(exact, flags):
    pb, lay = problem(), P._Layout(2)
    cost, lo, hi, a_mat, lb, ub = P._assemble(pb, COLS, IHAT, exact, **flags)
    dmat = np.hstack([FINAL, -FINAL])
    groups = [P._drift_rows(lay, dmat, FREE, TOL), P._along_track_rows(lay, dmat, FREE, pb.s)]
    if flags.get("ei", True):
        half = 0.5 * math.radians(pb.cfg.ei_angle_tol_deg)
        groups += [P._ei_direction_rows(lay, dmat, FREE, IHAT, s=pb.s, exact=exact, tg=math.tan(half)),
                   P._fov_rows(lay, pb.cfg, math.cos(half))]
    path_blocks, path_lb = P._path_rows(pb, COLS) if flags.get("path", True) else ([], [])
    burn, burn_ub = P._burn_magnitude_rows(pb, COLS)
    want = np.vstack([g.a for g in groups] + [b.toarray() for b in path_blocks] + [burn.toarray()])
    np.testing.assert_array_equal(a_mat.toarray(), want)
    np.testing.assert_array_equal(lb, np.concatenate([g.lb for g in groups] + [path_lb, [-np.inf] * len(burn_ub)]))
    np.testing.assert_array_equal(ub, np.concatenate([g.ub for g in groups] + [[np.inf] * len(path_lb), burn_ub]))
    np.testing.assert_array_equal(cost, P._objective(lay))
    np.testing.assert_array_equal((lo, hi), P._variable_bounds(pb, lay, COLS, exact=exact, target=True,
                                                               ei=flags.get("ei", True)))


# ----------------------------------------------------------------------------------- the recursive path (issue 42)
def _dense_problem(roe, chief, da_dot, cfg):
    """The problem with its dense path rows built (SPARSE_PATH off), as before issue 42."""
    saved = P.SPARSE_PATH
    P.SPARSE_PATH = False
    try:
        return P._build(np.asarray(roe, dtype=float), chief, da_dot, cfg, chief.t0 + 11400.0)
    finally:
        P.SPARSE_PATH = saved


@pytest.mark.parametrize("axes", ["TN", "RTN"])
def test_the_recursive_path_is_the_dense_path(axes):
    """Every burn vector x: the recursion's variables (Lambda_i = the dense row i times x, B_i the burns' growth of
    dl per step) satisfy its equality rows, and the two lags give back every dense entry, pre-burn rows included."""
    from test_acquisition import CHIEF, DA_DOT, TYPICAL

    cfg = P.AcquisitionConfig(axes=axes)
    pb = _dense_problem(TYPICAL, CHIEF, DA_DOT, cfg)
    cols = np.arange(pb.final.shape[1])
    post, pre = P._dense_path(dataclasses.replace(pb, path=None, path_pre=None), cols)
    scale = np.abs(pb.path).max()
    np.testing.assert_allclose(post, pb.path, rtol=0, atol=1e-12 * scale)
    if "R" in axes:
        np.testing.assert_allclose(pre, pb.path_pre, rtol=0, atol=1e-12 * scale)
    n_v = 2 * len(cols) + 3
    a_eq, b_eq, a_ge, b_ge, lo, hi = P._recursive_path(pb, cols, n_v)
    k = len(pb.epochs)
    assert a_eq.shape == (2 * k - 1, n_v + 2 * k - 1) and a_eq.nnz < 0.05 * pb.path.size
    rng = np.random.default_rng(3)
    x = rng.normal(size=len(cols)) * (rng.random(len(cols)) < 0.05)
    lam = pb.path @ x
    c_b = np.zeros(len(cols))
    own = pb.epoch_of
    nxt = own + 1 < k
    c_b[nxt] = pb.path[own[nxt] + 1, cols[nxt]] - pb.path[own, cols][nxt]
    b = np.array([c_b[own <= i] @ x[own <= i] for i in range(k - 1)])
    v = np.concatenate([np.maximum(x, 0), np.maximum(-x, 0), np.zeros(3), lam, b])
    np.testing.assert_allclose(a_eq @ v, b_eq, rtol=0, atol=1e-9 * scale)
    np.testing.assert_array_equal(lo[:k], pb.path_floor - pb.free_path)
    assert (a_ge is not None) == ("R" in axes)
    if a_ge is not None:
        np.testing.assert_allclose(a_ge @ v, pb.path_pre @ x, rtol=0, atol=1e-9 * scale)


@pytest.mark.parametrize("state", ["typical", "trailing", "fast"])
def test_both_forms_reach_the_same_optimum(state):
    """The recursive form is the same program: the continuous LP's optimum to 1e-9 (its vertex may differ: the LP
    is degenerate) and the quantized plan's delta-v."""
    from test_acquisition import CHIEF, DA_DOT, TYPICAL, roe_from

    roe = {"typical": TYPICAL, "trailing": roe_from(150.0, -20000.0, 550.0, 1.2, 420.0, 1.2),
           "fast": roe_from(-300.0, 15000.0, 480.0, -2.0, 380.0, -2.0)}[state]
    plans = {}
    saved = P.SPARSE_PATH
    try:
        for form in (False, True):
            P.SPARSE_PATH = form
            plans[form] = P.plan_acquisition(roe, CHIEF, DA_DOT, P.AcquisitionConfig())
    finally:
        P.SPARSE_PATH = saved
    assert plans[True].lp_dv == pytest.approx(plans[False].lp_dv, rel=1e-9)
    assert plans[True].total_dv == pytest.approx(plans[False].total_dv, rel=1e-9)
