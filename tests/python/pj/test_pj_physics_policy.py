"""ShakeScorer's object-level staircase policy (calibration on the first grasps' full grids).

Most tests inject constructed outcome functions in place of the physics (the staircase search
itself is the real ``_core.grasp.staircase_grid``), so which grids are monotone is known exactly;
one test runs the real physics to check the replay and the determinism.
"""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

import mgn
from mgn import _core
from mgn.errors import InvalidArgumentError
from mgn.pj import physics
from mgn.pj.physics import (
    ShakeOptions,
    ShakeScorer,
    calibrate_staircase,
    replay_staircase,
    shake_scores,
)

S = 5
CHECKS = 2


class Labels(SimpleNamespace):
    def __len__(self) -> int:
        return len(self.width)


def labels_of(n: int) -> Labels:
    """n distinct (but physically unused) grasp rows: the fake physics keys on the grasp index."""
    return Labels(
        approach=np.tile([0.0, 0.0, -1.0], (n, 1)),
        closing=np.tile([1.0, 0.0, 0.0], (n, 1)),
        p1=np.column_stack([np.full(n, -0.02), np.linspace(-0.01, 0.01, n), np.zeros(n)]),
        width=np.full(n, 0.04),
    )


def monotone(boundary: np.ndarray) -> np.ndarray:
    """(S, S) grid succeeding exactly where density index j < boundary[friction index i]."""
    return np.arange(S)[None, :] < np.asarray(boundary)[:, None]


def missed_cell_grid() -> np.ndarray:
    """A grid that succeeds everywhere but one cell the search never simulates (with CHECKS):
    found by brute force over the cells, so the search's score is wrong on it."""
    for c in range(S * S):
        g = np.ones((S, S), bool)
        g.flat[c] = False
        r = _core.grasp.staircase_grid(S, lambda i, j, g=g: bool(g[i, j]), CHECKS)
        if not r.simulated.flat[c]:
            return g
    raise AssertionError("the search simulates every cell: no missed cell to construct")


class FakePhysics:
    """Stands in for shake_scores: grasp g of the scorer's list (first_grasp_index + row) has the
    outcomes truth[g]; the staircase search is the real one. Logs every call."""

    def __init__(self, truth: np.ndarray):
        self.truth = truth
        self.calls: list[tuple[int, int, bool]] = []
        self.trials = 0

    def __call__(self, parts, mass, com, inertia, rows, gripper, options):
        first = options.first_grasp_index
        before = self.trials
        self.calls.append((first, len(rows), options.staircase))
        success = np.empty((len(rows), S, S), bool)
        for k in range(len(rows)):
            grid = self.truth[first + k]
            if options.staircase:
                r = _core.grasp.staircase_grid(
                    S, lambda i, j, grid=grid: bool(grid[i, j]), options.staircase_checks
                )
                success[k], self.trials = r.success, self.trials + r.trials
            else:
                success[k], self.trials = grid, self.trials + S * S
        return SimpleNamespace(
            score=success.sum(axis=(1, 2)) / (S * S),
            trial_success=success,
            num_trials=self.trials - before,
        )


def verdict(c: physics.StaircaseCalibration | None) -> tuple[int, int, bool] | None:
    """(calibration grasps, mismatches, staircase kept) of a calibration."""
    return None if c is None else (c.grasps, c.mismatches, c.staircase)


def score_with(monkeypatch, truth, **kw):
    kw.setdefault("calibration_tolerance", 0.0)  # the exact policy unless a test sets one
    fake = FakePhysics(truth)
    monkeypatch.setattr(physics, "shake_scores", fake)
    opts = ShakeOptions(grid=S, staircase=True, staircase_checks=CHECKS, num_threads=1)
    scorer = ShakeScorer(options=opts, progress=False, **kw)
    mesh = mgn.make_box([0.04, 0.05, 0.06])
    scores = scorer(mesh, labels_of(len(truth)))
    return scores, scorer, fake


def random_monotone(rng, n):
    return np.stack([monotone(np.sort(rng.integers(0, S + 1, S))) for _ in range(n)])


def truth_scores(truth):
    return (truth.sum(axis=(1, 2)) / (S * S)).astype(np.float32)


def test_monotone_object_keeps_the_staircase_after_calibration(monkeypatch):
    rng = np.random.default_rng(3)
    truth = random_monotone(rng, 40)
    scores, scorer, fake = score_with(monkeypatch, truth, calibration_grasps=8)
    np.testing.assert_array_equal(scores, truth_scores(truth))  # monotone: the search is exact
    assert verdict(scorer.last_calibration) == (8, 0, True)
    assert fake.calls == [(0, 8, False), (8, 32, True)]  # calibration grids, then the search
    assert fake.trials < 40 * S * S
    assert "staircase kept" in scorer.__name__
    assert "calibrated on 8" in scorer.__name__
    assert f"{CHECKS} checks, boundary verified in {S} of {S} friction rows" in scorer.__name__


def test_object_whose_calibration_disagrees_gets_the_full_grid_everywhere(monkeypatch):
    rng = np.random.default_rng(4)
    truth = random_monotone(rng, 30)
    bad = missed_cell_grid()
    truth[3] = bad  # a calibration grasp the search gets wrong ...
    truth[20] = bad  # ... and a later one, which the full grid then gets right
    assert replay_staircase(bad[None], CHECKS)[0][0] != bad.mean()
    scores, scorer, fake = score_with(monkeypatch, truth, calibration_grasps=8)
    np.testing.assert_array_equal(scores, truth_scores(truth))
    assert verdict(scorer.last_calibration) == (8, 1, False)
    assert fake.calls == [(0, 8, False), (8, 22, False)]
    assert fake.trials == 30 * S * S
    assert "full grid for the rest" in scorer.__name__


def test_the_verdict_depends_on_the_calibration_grasps_only(monkeypatch):
    """A non-monotone grid after the calibration grasps is scored by the search (wrongly here):
    the policy is decided once per object; and an allowed mismatch keeps the search."""
    rng = np.random.default_rng(5)
    truth = random_monotone(rng, 20)
    bad = missed_cell_grid()
    truth[12] = bad
    scores, scorer, _ = score_with(monkeypatch, truth, calibration_grasps=8)
    assert scorer.last_calibration is not None
    assert scorer.last_calibration.staircase
    expected = truth_scores(truth)
    expected[12] = replay_staircase(bad[None], CHECKS)[0][0]
    np.testing.assert_array_equal(scores, expected)
    assert scores[12] != truth_scores(truth)[12]

    truth[1] = bad
    _, one, _ = score_with(monkeypatch, truth, calibration_grasps=8, calibration_mismatches=1)
    assert verdict(one.last_calibration) == (8, 1, True)
    truth[2] = bad
    _, two, _ = score_with(monkeypatch, truth, calibration_grasps=8, calibration_mismatches=1)
    assert verdict(two.last_calibration) == (8, 2, False)


def test_no_calibration_and_small_objects(monkeypatch):
    rng = np.random.default_rng(6)
    truth = random_monotone(rng, 5)
    truth[1] = missed_cell_grid()
    plain, scorer, fake = score_with(monkeypatch, truth, calibration_grasps=0)
    assert scorer.last_calibration is None
    assert fake.calls == [(0, 5, True)]
    assert plain[1] != truth_scores(truth)[1]
    # Fewer grasps than calibration grasps: all on the full grid, nothing left.
    few, scorer, fake = score_with(monkeypatch, truth, calibration_grasps=16)
    np.testing.assert_array_equal(few, truth_scores(truth))
    assert verdict(scorer.last_calibration) == (5, 1, False)
    assert fake.calls == [(0, 5, False)]


def test_progress_pieces_keep_every_grasps_index(monkeypatch):
    """With the progress bar the grasps are scored in pieces (16 per thread); each must keep its
    own index (first_grasp_index), so the scores equal the scores without it."""
    rng = np.random.default_rng(7)
    truth = random_monotone(rng, 45)
    for bad in (None, 5):
        if bad is not None:
            truth[bad] = missed_cell_grid()
        quiet, _, _ = score_with(monkeypatch, truth, calibration_grasps=10)
        fake = FakePhysics(truth)
        monkeypatch.setattr(physics, "shake_scores", fake)
        opts = ShakeOptions(grid=S, staircase=True, staircase_checks=CHECKS, num_threads=1)
        shown = ShakeScorer(options=opts, progress=True, calibration_grasps=10)(
            mgn.make_box([0.04, 0.05, 0.06]), labels_of(len(truth))
        )
        np.testing.assert_array_equal(shown, quiet)
        assert [c[0] for c in fake.calls] == [0, 10, 26, 42]


def test_calibrate_staircase_against_brute_force():
    rng = np.random.default_rng(8)
    grids = random_monotone(rng, 12)
    c = calibrate_staircase(grids, CHECKS)
    assert verdict(c) == (12, 0, True)
    grids[[2, 7]] = missed_cell_grid()
    assert verdict(calibrate_staircase(grids, CHECKS)) == (12, 2, False)
    assert calibrate_staircase(grids, CHECKS, 2).staircase
    # With every cell checked the search is exact on any grid.
    assert calibrate_staircase(grids, S * S).mismatches == 0
    with pytest.raises(InvalidArgumentError, match="max_mismatches"):
        calibrate_staircase(grids, CHECKS, -1)
    with pytest.raises(InvalidArgumentError, match="trial_success"):
        replay_staircase(np.ones((2, 3, 4), bool), CHECKS)


@pytest.mark.parametrize("field", ["calibration_grasps", "calibration_mismatches"])
def test_bad_calibration_settings_are_rejected(field):
    scorer = ShakeScorer(**{field: -1})  # type: ignore[arg-type]
    with pytest.raises(InvalidArgumentError, match=f"ShakeScorer.{field}"):
        scorer(mgn.make_box([0.04, 0.05, 0.06]), labels_of(3))


def test_real_physics_replay_and_calibration_are_deterministic():
    """Real shake trials on a box: the staircase replayed on full grids gives the real search's
    scores and trial counts, and the calibrated scorer gives the same scores with 1 or 2 threads
    and with or without the progress bar, its calibration grasps the full grid's scores."""
    mesh = mgn.make_box([0.04, 0.05, 0.05])
    n = 6
    labels = labels_of(n)
    labels.p1[:, 1] = np.linspace(-0.02, 0.02, n)
    labels.p1[:, 2] = np.linspace(0.015, -0.015, n)
    props = mgn.geometry.mass_properties(mesh, 3000.0)
    rows = physics.grasp_rows(
        np.column_stack([labels.approach, labels.closing, labels.p1, labels.width])
    )
    base = ShakeOptions(grid=3, friction_range=(0.05, 0.8), staircase_checks=1, num_threads=2)
    args = (mesh, props.mass, props.center_of_mass, props.inertia, rows)
    full = shake_scores(*args, options=base)
    stair = shake_scores(*args, options=replace(base, staircase=True))
    replayed, trials = replay_staircase(full.trial_success, base.staircase_checks)
    np.testing.assert_array_equal(replayed, stair.score)
    np.testing.assert_array_equal(trials, stair.trial_simulated.sum(axis=(1, 2)))
    assert 0 < full.score.mean() < 1  # some grids are mixed: the search has work to do
    results = []
    for threads in (1, 2):
        for progress in (False, True):
            opts = replace(base, staircase=True, num_threads=threads)
            scorer = ShakeScorer(3000.0, options=opts, progress=progress, calibration_grasps=3)
            results.append((scorer(mesh, labels), scorer.last_calibration))
    chosen = calibrate_staircase(full.trial_success[:3], 1, 0, -1, physics.CALIBRATION_TOLERANCE)
    for got, cal in results:
        np.testing.assert_array_equal(got, results[0][0])
        assert cal == results[0][1] == chosen
    np.testing.assert_array_equal(results[0][0][:3], full.score[:3].astype(np.float32))
    search = physics.search_of(chosen, replace(base, staircase=True))
    rest = full.score
    if search.staircase:
        rest, _ = replay_staircase(
            full.trial_success, search.staircase_checks, search.to_core().staircase_verified_rows()
        )
    np.testing.assert_array_equal(results[0][0][3:], rest[3:].astype(np.float32))


def test_cli_calibration_flag_reaches_the_scorer():
    from mgn.cli.main import build_parser
    from mgn.cli.pj import _physics_scorer
    from mgn.hardware import default_gripper

    parser = build_parser()
    args = parser.parse_args(["pj", "label", "x.obj", "--physics-calibration", "4"])
    assert _physics_scorer(args, default_gripper()).calibration_grasps == 4
    args = parser.parse_args(["pj", "label", "x.obj"])
    assert _physics_scorer(args, default_gripper()).calibration_grasps == 32
    assert _physics_scorer(args, default_gripper()).options.staircase_checks == 0


def test_default_checks_follow_the_calibration():
    """Without a user's value the staircase checks are 0 with the object-level calibration (it
    catches the objects with isolated failing cells) and the search's own 6 without it; a given
    value is kept either way (API, pipeline config and CLI agree)."""
    from mgn.cli.main import build_parser
    from mgn.cli.pj import _physics_scorer
    from mgn.hardware import default_gripper
    from mgn.pipeline.config import load_config
    from mgn.pipeline.label_cache import shake_options

    assert physics.default_staircase_checks(32) == physics.CALIBRATED_STAIRCASE_CHECKS == 0
    assert physics.default_staircase_checks(0) == ShakeOptions().staircase_checks == 6
    assert ShakeScorer().calibration_grasps > 0
    assert ShakeScorer().options.staircase_checks == 0
    # The boundary of the lower half of the friction rows with calibration, every row without.
    assert (
        physics.default_staircase_verify_share(32)
        == 0.5
        == physics.CALIBRATED_STAIRCASE_VERIFY_SHARE
    )
    assert physics.default_staircase_verify_share(0) == ShakeOptions().staircase_verify_share == 1
    assert ShakeScorer().options.staircase_verify_share == 0.5
    parser = build_parser()
    for argv, checks in (
        ([], 0),
        (["--physics-calibration", "0"], 6),
        (["--physics-checks", "3"], 3),
        (["--physics-calibration", "0", "--physics-checks", "2"], 2),
    ):
        args = parser.parse_args(["pj", "label", "x.obj", *argv])
        share = 1.0 if "--physics-calibration" in argv else 0.5
        options = _physics_scorer(args, default_gripper()).options
        assert options.staircase_checks == checks
        assert options.staircase_verify_share == share
        ol = {}
        if "--physics-calibration" in argv:
            ol["physics_calibration"] = 0
        if "--physics-checks" in argv:
            ol["physics_checks"] = int(argv[-1])
        config = load_config({"object_labels": ol})
        assert config.object_labels.staircase_checks == checks
        assert shake_options(config).staircase_verify_share == share


def test_verified_rows_are_the_lowest_frictions():
    """The boundary checks cover the rows i < ceil(share * S): a grid failing only at the
    hardest cell of such a row is scored exactly (the check finds it), one failing only in a
    higher row is taken for a grid that succeeds everywhere; the walk's trials drop by one per
    row left out; -1 (and S) verify every row."""
    for rows in (-1, 0, 2, S):
        for i in range(1, S):
            g = np.ones((S, S), bool)
            g[i, S - 1] = False
            r = _core.grasp.staircase_grid(S, lambda a, b, g=g: bool(g[a, b]), 0, rows)
            verified = rows < 0 or i < rows
            assert r.fallback == verified
            assert np.asarray(r.success).all() == (not verified)
        everywhere = np.ones((S, S), bool)
        r = _core.grasp.staircase_grid(S, lambda a, b: True, 0, rows)
        assert np.array_equal(np.asarray(r.success), everywhere)
        assert r.trials == 1 + (S if rows < 0 else rows)
    opts = ShakeOptions(grid=10, staircase_verify_share=0.5).to_core()
    assert opts.staircase_verified_rows() == 5
    assert ShakeOptions(grid=5, staircase_verify_share=0.5).to_core().staircase_verified_rows() == 3
    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(InvalidArgumentError, match="staircase_verify_share"):
            shake_scores(
                mgn.make_box([0.04, 0.04, 0.04]),
                0.1,
                np.zeros(3),
                np.eye(3) * 1e-4,
                np.zeros((0, 10)),
                options=ShakeOptions(staircase_verify_share=bad),
            )


def test_zero_checks_still_verify_every_rows_boundary():
    """With 0 checks the search still simulates the inferred cell next to every row's boundary:
    a grid that succeeds everywhere but one such cell is scored exactly, while
    a failing cell away from the boundaries is missed, which is what the calibration is for."""
    caught = missed = 0
    for c in range(S * S):
        g = np.ones((S, S), bool)
        g.flat[c] = False
        r = _core.grasp.staircase_grid(S, lambda i, j, g=g: bool(g[i, j]), 0)
        if c % S == S - 1:  # the hardest cell of a row: the boundary of an all-success row
            # (row 0's is monotone and found by the walk; the others are caught by a check)
            assert np.array_equal(np.asarray(r.success, bool).reshape(S, S), g)
            assert r.fallback == (c != S - 1)
            caught += 1
        elif not np.asarray(r.simulated).flat[c]:
            assert not r.fallback
            assert np.asarray(r.success).all()
            missed += 1
    assert caught == S
    assert missed > 0


# ------------------------------------------------------------- the tolerance (error bound)


def holed(rng: np.random.Generator, n: int, p_hole: float, holes: int) -> np.ndarray:
    """n monotone grids, each with probability p_hole given ``holes`` isolated failing cells
    inside its success region (what real cans and bottles show)."""
    grids = random_monotone(rng, n)
    for g in grids:
        if rng.random() < p_hole:
            for _ in range(holes):
                inside = np.argwhere(g)
                if len(inside):
                    g[tuple(inside[rng.integers(len(inside))])] = False
    return grids


def one_hole_grids():
    """Every grid that succeeds everywhere but one cell."""
    for c in range(S * S):
        g = np.ones((S, S), bool)
        g.flat[c] = False
        yield g


def test_binomial_upper_bound_is_clopper_pearsons():
    from scipy.stats import beta

    for m, n in ((0, 32), (1, 32), (5, 32), (3, 8), (0, 1), (31, 32)):
        assert physics._binomial_upper(m, n) == pytest.approx(
            beta.ppf(0.95, m + 1, n - m), abs=1e-9
        )
    assert physics._binomial_upper(4, 4) == 1.0


def test_error_bound_by_hand():
    cell = 1.0 / 100
    # No wrong calibration grasp of 32: the rate's bound 1 - 0.05^(1/32) times one cell.
    assert physics.error_bound(np.zeros(32), cell) == pytest.approx(
        (1 - 0.05 ** (1 / 32)) * cell, rel=1e-9
    )
    # Two wrong of 32 by 0.02 and 0.06: the rate's bound times their mean size 0.04.
    e = np.zeros(32)
    e[[3, 9]] = (0.02, 0.06)
    assert physics.error_bound(e, cell) == pytest.approx(
        physics._binomial_upper(2, 32) * 0.04, rel=1e-9
    )
    assert physics.error_bound(np.ones(4), cell) == 1.0


@pytest.mark.parametrize(("p_hole", "holes"), [(0.0, 1), (0.05, 1), (0.2, 1), (0.5, 3)])
def test_the_error_bound_holds_on_the_grasps_after_the_calibration(p_hole, holes):
    """On populations of constructed grids (monotone, rarely and often holed), the bound that
    the calibration records for the search it chose holds for the object's other grasps in
    >= 90 % of the draws (it is a 95 % bound), and the chosen search's error is within the
    tolerance wherever the bound is."""
    tol = 0.02  # a cell of the 5 x 5 test grid is 0.04
    held, within = 0, 0
    draws = 30
    for seed in range(draws):
        grids = holed(np.random.default_rng(seed), 160, p_hole, holes)
        cal, rest = grids[:32], grids[32:]
        c = calibrate_staircase(cal, CHECKS, 0, -1, tol)
        search = physics.search_of(c, ShakeOptions(grid=S, staircase=True, staircase_checks=CHECKS))
        truth = rest.mean(axis=(1, 2))
        got = truth
        if search.staircase:
            got, _ = replay_staircase(rest, search.staircase_checks, -1)
        err = float(np.abs(got - truth).mean())
        held += err <= c.error_bound + 1e-12
        within += c.error_bound <= tol or c.search == "full grid"
    assert held >= 0.9 * draws
    assert within == draws
    if p_hole == 0.0:
        assert c.search == "staircase"
        assert c.mismatches == 0


def test_tolerance_picks_the_cheapest_search_within_it(monkeypatch):
    """A holed object: the plain search misses cells on several calibration grasps, the
    checked search does not; with a tolerance the object's other grasps get the checked
    search (fewer trials than the full grid, the holes found), without one the full grid."""
    rng = np.random.default_rng(11)
    truth = random_monotone(rng, 60)
    checked = physics.CHECKED_STAIRCASE_CHECKS
    bad = next(
        g
        for g in one_hole_grids()
        if replay_staircase(g[None], CHECKS)[0][0] != g.mean()
        and replay_staircase(g[None], checked)[0][0] == g.mean()
    )
    for g in (1, 4, 6, 30, 50):
        truth[g] = bad
    assert replay_staircase(bad[None], physics.CHECKED_STAIRCASE_CHECKS)[0][0] == bad.mean()
    scores, scorer, fake = score_with(
        monkeypatch, truth, calibration_grasps=8, calibration_tolerance=0.02
    )
    c = scorer.last_calibration
    assert c is not None
    assert c.search == "checked staircase"
    assert c.staircase
    assert c.mismatches == 0
    assert c.error_bound <= 0.02
    np.testing.assert_array_equal(scores, truth_scores(truth))  # the checks find the holes
    assert fake.trials < 60 * S * S
    assert "checked staircase for the rest" in scorer.__name__
    _, exact, fake0 = score_with(monkeypatch, truth, calibration_grasps=8)
    assert exact.last_calibration is not None
    assert exact.last_calibration.search == "full grid"
    assert fake0.trials == 60 * S * S


def test_holes_no_search_visits_get_the_full_grid():
    """10 x 10 grids that succeed everywhere but in cells none of the searches simulates on
    an all-success grid: every search scores them 1.0, so none is within the tolerance and
    the object gets the full grid (on a 5 x 5 grid the thorough search visits every cell)."""
    s10 = 10
    unseen = np.ones((s10, s10), bool)
    for checks, rows in (
        (0, -1),
        (physics.CHECKED_STAIRCASE_CHECKS, -1),
        (physics.SAMPLED_STAIRCASE_CHECKS, 0),
        (physics.THOROUGH_STAIRCASE_CHECKS, -1),
    ):
        r = _core.grasp.staircase_grid(s10, lambda i, j: True, checks, rows)
        unseen &= ~np.asarray(r.simulated)
    cells = np.argwhere(unseen)
    assert len(cells) >= 3
    grids = np.ones((32, s10, s10), bool)
    for g in range(0, 32, 2):  # every other grasp misses three cells no search looks at
        for i, j in cells[:3]:
            grids[g, i, j] = False
    c = calibrate_staircase(grids, 0, 0, -1, physics.CALIBRATION_TOLERANCE)
    assert c.search == "full grid"
    assert not c.staircase
    assert c.mismatches == 16
    assert c.trials_per_grasp == s10 * s10
    opts = physics.search_of(c, ShakeOptions(staircase=True))
    assert not opts.staircase


def test_sampled_staircase_finds_holes_away_from_the_boundary_at_fewer_trials():
    """10 x 10 grids that succeed everywhere but one isolated cell in every other grasp, at a
    cell the sampled search's golden-ratio checks visit and the checked search does not: the
    plain and checked searches miss it on 16 of 32 calibration grasps (bound above the
    tolerance), the sampled search finds it (a contradiction: the full grid) and is chosen.
    On a grid that succeeds everywhere it simulates 1 + 24 cells, the thorough search also
    the cell next to every row's boundary: 1 + 10 + 24."""
    s10 = 10
    sampled = physics.SAMPLED_STAIRCASE_CHECKS

    def visited(checks: int, rows: int) -> tuple[np.ndarray, int]:
        r = _core.grasp.staircase_grid(s10, lambda i, j: True, checks, rows)
        return np.asarray(r.simulated, bool).reshape(s10, s10), r.trials

    seen_sampled, trials_sampled = visited(sampled, 0)
    seen_checked, _ = visited(physics.CHECKED_STAIRCASE_CHECKS, -1)
    _, trials_thorough = visited(physics.THOROUGH_STAIRCASE_CHECKS, -1)
    assert trials_sampled == 1 + sampled
    assert trials_thorough == 1 + s10 + physics.THOROUGH_STAIRCASE_CHECKS
    cells = np.argwhere(seen_sampled & ~seen_checked)
    assert len(cells) >= 1
    i, j = cells[0]
    grids = np.ones((32, s10, s10), bool)
    grids[::2, i, j] = False
    c = calibrate_staircase(grids, 0, 0, 5, physics.CALIBRATION_TOLERANCE)
    assert c.search == "sampled staircase"
    assert c.mismatches == 0
    assert c.error_bound <= physics.CALIBRATION_TOLERANCE
    opts = physics.search_of(c, ShakeOptions(grid=s10, staircase=True))
    assert opts.staircase_checks == sampled
    assert opts.to_core().staircase_verified_rows() == 0
    scores, _ = replay_staircase(grids, sampled, opts.to_core().staircase_verified_rows())
    np.testing.assert_array_equal(scores, grids.mean(axis=(1, 2)))
    checked_scores, _ = replay_staircase(grids, physics.CHECKED_STAIRCASE_CHECKS, -1)
    assert np.count_nonzero(checked_scores != grids.mean(axis=(1, 2))) == 16


def test_the_label_metadata_records_the_estimator(monkeypatch):
    monkeypatch.setattr(
        physics, "shake_scores", FakePhysics(random_monotone(np.random.default_rng(13), 400))
    )
    mesh = mgn.make_box([0.03, 0.04, 0.05])
    scorer = ShakeScorer(
        options=ShakeOptions(grid=S, staircase=True, staircase_checks=CHECKS),
        progress=False,
        calibration_grasps=4,
    )
    labels = mgn.pj.label_object(
        mesh, mass=0.1, com=[0, 0, 0], num_points=40, physics=scorer, max_grasps=30
    )
    est = labels.metadata["pj_physics_estimator"]
    assert est["search"] == "staircase"
    assert est["calibration_grasps"] == 4
    assert est["error_bound_95"] == pytest.approx(
        physics.error_bound(np.zeros(4), 1 / S**2), abs=1e-6
    )
    assert len(labels) == 30
    assert labels.metadata["pj_max_grasps"] == 30
    assert labels.metadata["pj_num_found"] > 30
    assert np.isfinite(labels.quality_score_simulation).all()


def test_bad_tolerance_is_named():
    with pytest.raises(InvalidArgumentError, match=r"ShakeScorer.calibration_tolerance"):
        ShakeScorer(calibration_tolerance=1.5)(mgn.make_box([0.04, 0.05, 0.06]), labels_of(3))
    with pytest.raises(InvalidArgumentError, match="tolerance"):
        calibrate_staircase(np.ones((2, S, S), bool), CHECKS, 0, -1, -0.1)


def test_two_stage_calibration_stops_after_the_first_stage(monkeypatch):
    """Monotone grids: the plain search reproduces the first stage's grids, so the calibration
    stops there and the object's other grasps (from the 13th) get the search."""
    rng = np.random.default_rng(21)
    truth = random_monotone(rng, 60)
    scores, scorer, fake = score_with(
        monkeypatch, truth, calibration_grasps=32, calibration_min_grasps=12
    )
    np.testing.assert_array_equal(scores, truth_scores(truth))
    assert verdict(scorer.last_calibration) == (12, 0, True)
    assert fake.calls == [(0, 12, False), (12, 48, True)]
    assert "calibrated on 12 full grids" in scorer.__name__
    # One stage (0) simulates all 32 calibration grids, as does a first stage of 32 or more.
    for first_stage in (0, 32, 40):
        _, one, fake1 = score_with(
            monkeypatch, truth, calibration_grasps=32, calibration_min_grasps=first_stage
        )
        assert verdict(one.last_calibration) == (32, 0, True)
        assert fake1.calls == [(0, 32, False), (32, 28, True)]
        assert fake1.trials > fake.trials


def test_two_stage_calibration_goes_on_when_the_plain_search_fails(monkeypatch):
    """A grid the plain search gets wrong among the first 12: the calibration simulates the
    other 20 calibration grids and chooses on all 32. With the exact policy that is the full
    grid; with a tolerance whose bound one wrong grasp of 12 exceeds (CP(1, 12) x one cell =
    0.0136 > 0.01) but one of 32 does not (0.0056), the plain search on all 32."""
    rng = np.random.default_rng(22)
    truth = random_monotone(rng, 60)
    truth[3] = missed_cell_grid()
    scores, scorer, fake = score_with(
        monkeypatch, truth, calibration_grasps=32, calibration_min_grasps=12
    )
    np.testing.assert_array_equal(scores, truth_scores(truth))
    assert verdict(scorer.last_calibration) == (32, 1, False)
    assert fake.calls == [(0, 12, False), (12, 20, False), (32, 28, False)]
    assert fake.trials == 60 * S * S

    cell = 1.0 / (S * S)
    assert physics._binomial_upper(1, 12) * cell > 0.01 >= physics._binomial_upper(1, 32) * cell
    _, tol, fake_tol = score_with(
        monkeypatch,
        truth,
        calibration_grasps=32,
        calibration_min_grasps=12,
        calibration_tolerance=0.01,
    )
    c = tol.last_calibration
    assert c is not None
    assert (c.grasps, c.search, c.mismatches) == (32, "staircase", 1)
    assert c.error_bound == pytest.approx(physics._binomial_upper(1, 32) * cell)
    assert fake_tol.calls == [(0, 12, False), (12, 20, False), (32, 28, True)]


@pytest.mark.parametrize(("p_hole", "holes"), [(0.0, 1), (0.05, 1), (0.2, 1), (0.5, 3)])
def test_the_two_stage_bound_holds_on_the_grasps_after_the_calibration(monkeypatch, p_hole, holes):
    """As the one-stage test above, through the scorer with the two-stage calibration (12,
    then 32): the bound it records holds for the scores of the grasps after its calibration
    grasps in >= 90 % of the draws, and is within the tolerance unless the full grid was
    chosen."""
    tol = 0.02
    held, within, early = 0, 0, 0
    draws = 30
    for seed in range(draws):
        truth = holed(np.random.default_rng(100 + seed), 160, p_hole, holes)
        scores, scorer, _ = score_with(
            monkeypatch,
            truth,
            calibration_grasps=32,
            calibration_min_grasps=12,
            calibration_tolerance=tol,
        )
        c = scorer.last_calibration
        assert c is not None
        k = c.grasps
        assert k in (12, 32)
        early += k == 12
        err = float(np.abs(scores[k:] - truth_scores(truth)[k:]).mean())
        held += err <= c.error_bound + 1e-6
        within += c.error_bound <= tol or c.search == "full grid"
    assert held >= 0.9 * draws
    assert within == draws
    if p_hole == 0.0:
        assert early == draws  # monotone grids: always the first stage alone
