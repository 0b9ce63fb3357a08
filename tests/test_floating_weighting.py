"""Weighted least squares of the floating-base identification, against logs the tests generate
(``test_floating_cli.simulate``: Pinocchio's rnea at random states, the root's generalized
force carried by contact wrenches split among the contact links in a known way, the joint
torques the rest) with Gaussian noise of different known sizes on the joint torques, the
wrenches' forces and their moments (10:1 between each). The standard deviations the fit gives
are checked against the estimate's actual error from the true base values (those of the
description's parameters): ``z = (estimate - truth) / std`` over the base values, pooled over a
few logs, has an RMS near 1 and 95 % of its values within 3; each coordinate's noise the fit
estimates is checked against the noise the test added (through Pinocchio's Jacobians)."""

from __future__ import annotations

import functools
import json

import mindyn
import numpy as np
import pytest
from conftest import assert_close, cli
from mindyn.identification.floating import FloatingLog, identify_floating
from random_tree import random_tree_urdf
from test_floating_cli import FEET, SOLO, library, pair, simulate, write
from test_multibody import FLOATING

# noise standard deviations (joint torques N m, wrench forces N, wrench moments N m)
NOISY_FORCES = (0.01, 1.0, 0.1)
NOISY_MOMENTS = (0.01, 0.1, 1.0)
NOISY_TORQUES = (1.0, 0.1, 0.01)
MIXES = {"moments": NOISY_MOMENTS, "forces": NOISY_FORCES, "torques": NOISY_TORQUES}
TALOS_FEET = ["leg_left_6_link", "leg_right_6_link"]


@functools.cache
def case(name: str):
    """(robot, pin model, contact links, samples per log, logs pooled, wrenches in the links'
    axes) of a test robot: Solo12 on its four feet, TALOS on its two, a random tree of seven
    revolute joints on a free-flyer with two leaves in contact."""
    if name == "tree":
        import tempfile
        from pathlib import Path

        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "tree.urdf"
            robot, model = pair(str(random_tree_urdf(path, n=7, seed=3, moving=("revolute",))))
        children = set(robot.parents)
        leaves = [robot.link_names[k + 1] for k in range(robot.n) if k not in children][:2]
        return robot, model, leaves, 150, 4, True
    if name == "solo12":
        return (*pair(SOLO), FEET, 300, 3, False)
    return (*pair(str(FLOATING["talos"])), TALOS_FEET, 120, 2, False)


def as_log(robot, table: np.ndarray, contacts: list[str], local: bool) -> FloatingLog:
    """The FloatingLog of a simulated table (its columns q, dq, ddq, tau, wrenches)."""
    nq, nv = robot.nq, robot.nv
    a = nq + 2 * nv + nv - 6
    return FloatingLog(
        table[:, :nq],
        table[:, nq : nq + nv],
        table[:, nq + nv : nq + 2 * nv],
        table[:, nq + 2 * nv : a],
        {c: table[:, a + 6 * i : a + 6 * i + 6] for i, c in enumerate(contacts)},
        wrench_frame="local" if local else "world",
    )


def figures(z: np.ndarray) -> tuple[float, float]:
    """(RMS of z, fraction of z within 3)."""
    return float(np.sqrt(np.mean(z**2))), float(np.mean(np.abs(z) <= 3.0))


@pytest.mark.parametrize("name", ["solo12", "talos", "tree"])
def test_weighted_standard_deviations_describe_the_error_where_ordinary_ones_do_not(name):
    """For each noise mix (moments, forces or joint torques noisiest, 100:10:1): the default
    (weighted) fit's z has an RMS within [0.7, 1.3] and at least 95 % within 3, pooled over the
    logs; its noise per coordinate is the added noise's RMS within 25 %; on a validation log its
    prediction misses the measured generalized forces by no more than 1.2 times the noise
    (overall) and twice (per coordinate). Ordinary least squares (one noise level for every
    equation), on the same logs, misses the z criterion in at least one of the mixes."""
    robot, model, contacts, m, pool, local = case(name)
    base = mindyn.base_parameters(robot, method="numerical")
    truth = base.values(robot.params)
    ols_off = []
    for mix, sizes in MIXES.items():
        rng = np.random.default_rng(60)
        logs, noises, z = [], [], []
        for _ in range(pool):
            table, _, noise = simulate(
                robot, model, contacts, rng, m, noise=True, local=local, sizes=sizes
            )
            logs.append(as_log(robot, table, contacts, local))
            noises.append(noise)
            result = identify_floating(robot, logs[-1], base=base)  # the default: weighted
            z.append((result.values - truth) / result.std)
        rms, within = figures(np.concatenate(z))
        table, _, noise = simulate(
            robot, model, contacts, rng, 60, noise=True, local=local, sizes=sizes
        )
        val = as_log(robot, table, contacts, local)
        miss = result.residual(val).reshape(60, -1)
        ratio = np.sqrt(np.mean(miss**2)) / np.sqrt(np.mean(noise**2))
        per = np.sqrt(np.mean(miss**2, axis=0) / np.mean(noise**2, axis=0))
        print(
            f"{name}, {mix} noisiest: weighted z RMS {rms:.3f}, within 3 {within:.3f}; "
            f"validation / noise {ratio:.3f}, worst coordinate {per.max():.2f}"
        )
        assert 0.7 <= rms <= 1.3 and within >= 0.95, (rms, within)
        assert ratio <= 1.2 and per.max() <= 2.0, (ratio, per)
        # the noise the fit estimated per coordinate is the one added, through the Jacobians
        assert result.weighted and result.coordinate_sigma is not None
        added = np.sqrt(np.mean(noises[-1] ** 2, axis=0))
        assert_close(result.coordinate_sigma, added, 0.25, f"{name} noise per coordinate ({mix})")
        assert "per coordinate" in result.weighting and "settled" in result.weighting
        assert 0.8 < result.sigma < 1.25  # the weighted residual's, dimensionless
        ols = [identify_floating(robot, log, base=base, weighted=False) for log in logs]
        o_rms, o_within = figures(np.concatenate([(r.values - truth) / r.std for r in ols]))
        o_miss = ols[-1].residual(val).reshape(60, -1)
        o_per = np.sqrt(np.mean(o_miss**2, axis=0) / np.mean(noise**2, axis=0))
        o_ratio = np.sqrt(np.mean(o_miss**2)) / np.sqrt(np.mean(noise**2))
        print(
            f"{name}, {mix} noisiest: ordinary z RMS {o_rms:.3f}, within 3 {o_within:.3f}; "
            f"validation / noise {o_ratio:.3f}, worst coordinate {o_per.max():.2f}"
        )
        ols_off.append(not (0.7 <= o_rms <= 1.3 and o_within >= 0.95))
        assert not ols[-1].weighted and ols[-1].coordinate_sigma is None
    assert any(ols_off), "ordinary least squares met the criterion in every mix"


def test_noise_free_coordinates_are_fitted_exactly_with_their_weight_bounded():
    """TALOS on its feet with noise on the wrenches only: the coordinates no contact reaches
    (torso, arms, head: no noise) are fitted to round-off, their sigma raised to the floor and
    named; the weighted estimate reproduces their generalized forces where ordinary least
    squares spreads the wrenches' noise into them; its z figures still hold."""
    robot, model, contacts, m, _, _ = case("talos")
    base = mindyn.base_parameters(robot, method="numerical")
    truth = base.values(robot.params)
    table, _, noise = simulate(
        robot, model, contacts, np.random.default_rng(8), m, noise=True, sizes=(0.0, 1.0, 0.1)
    )
    log = as_log(robot, table, contacts, False)
    exact = np.flatnonzero(np.all(noise == 0.0, axis=0))
    assert len(exact) == 20  # the torso's, arms' and head's joints
    result = identify_floating(robot, log, base=base)
    predicted, measured = result.forces(log)
    scale = np.abs(measured[:, exact]).max()
    miss = np.abs(predicted - measured)[:, exact].max() / scale
    print(f"largest relative miss on the exact coordinates, weighted: {miss:.2g}")
    assert miss < 1e-8
    ordinary = identify_floating(robot, log, base=base, weighted=False)
    predicted, _ = ordinary.forces(log)
    ordinary_miss = np.abs(predicted - measured)[:, exact].max() / scale
    print(f"largest relative miss on the exact coordinates, ordinary: {ordinary_miss:.2g}")
    assert ordinary_miss > 1e-4
    assert result.weighted
    rows = ", ".join(str(g + 1) for g in exact)
    assert f"{len(exact)} coordinate(s) (rows {rows} of each sample) fitted to round-off" in (
        result.weighting
    )
    floor = result.coordinate_sigma.max() * 1e-9
    assert_close(result.coordinate_sigma[exact], floor, 1e-12, "floored sigma")
    rms, within = figures((result.values - truth) / result.std)
    print(f"talos, exact joint torques: z RMS {rms:.3f}, within 3: {within:.3f}")
    assert 0.7 <= rms <= 1.3 and within >= 0.95, (rms, within)


def test_noise_free_logs_are_fitted_by_ordinary_least_squares_and_say_why():
    robot, model, contacts, _, _, _ = case("solo12")
    base = mindyn.base_parameters(robot, method="numerical")
    table, _, _ = simulate(robot, model, contacts, np.random.default_rng(3), 40)
    result = identify_floating(robot, as_log(robot, table, contacts, False), base=base)
    assert_close(result.values, base.values(robot.params), 1e-6, "noise-free, weighted default")
    assert not result.weighted and result.coordinate_sigma is None
    assert result.weighting.startswith("none: the ordinary fit's residual is at round-off")


def test_identify_takes_ols_and_its_json_is_the_library_report(tmp_path):
    """``mindyn identify --root-joint floating``: weighted by default, ``--ols`` ordinary; the
    JSON of each equals run_floating(..., weighted=...).to_dict(), states the weighting and the
    noise per coordinate, and the text says which estimator."""
    robot, model = pair(SOLO)
    rng = np.random.default_rng(13)
    table, header, noise = simulate(robot, model, FEET, rng, 200, noise=True, sizes=NOISY_MOMENTS)
    fit = write(tmp_path / "fit.csv", table, header)
    out = tmp_path / "id.json"
    argv = ["identify", SOLO, fit, "--root-joint", "floating", "--json", out]
    text = cli(*argv)
    doc = json.loads(out.read_text())
    assert doc == json.loads(json.dumps(library(robot, [fit]).to_dict()))
    assert doc["weighted"] is True and doc["estimator"].startswith("weighted least squares")
    assert len(doc["coordinate_sigma"]) == robot.nv == len(doc["coordinates"])
    added = np.sqrt(np.mean(noise**2, axis=0))
    assert_close(doc["coordinate_sigma"], added, 0.25, "CLI noise per coordinate")
    assert "(weighted least squares, per coordinate)" in text and "noise sigma" in text
    assert "weighting      per coordinate" in text
    text = cli(*argv, "--ols")
    ols = json.loads(out.read_text())
    from mindyn.identification.floating_workflow import load_floating_logs, run_floating

    report = run_floating(robot, load_floating_logs([fit], robot), weighted=False)
    assert ols == json.loads(json.dumps(report.to_dict()))
    assert ols["weighted"] is False and ols["coordinate_sigma"] is None
    assert ols["estimator"] == "ordinary least squares" and "(ordinary least squares)" in text
    assert ols["values"] != doc["values"]
    # the base-link model is weighted too (the root's six coordinates), and takes --ols
    cli(*argv, "--model", "base")
    link = json.loads(out.read_text())
    assert link["weighted"] is True and len(link["coordinate_sigma"]) == 6
    assert_close(link["coordinate_sigma"], added[:6], 0.25, "CLI noise per root coordinate")
