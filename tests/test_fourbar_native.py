"""The four-bar construction's compiled evaluation (synth.mechanisms.fourbar.compiled) against
its numpy version: the same validity and feasibility, the same NaNs, the same numbers to
rounding, over random problems (fixed links, bounds, rods, both objectives) and points."""

import math

import numpy as np
import pytest

from synth.errors import Unreachable
from synth.mechanisms import crank_rocker_slider, drag_link_slider, get
from synth.mechanisms.fourbar.solver import FourBar
from synth.synthesis.formulation import relevant
from synth.synthesis.search import Spec, Targets, build_problem, variants

ROLES = {"crank_rocker_slider": crank_rocker_slider.ROLES,
         "drag_link_slider": drag_link_slider.ROLES}  # fmt: skip
KEYS = ("f", "size", "k", "r5", "l", "h", "rod_cos", "slack")


def problems(mtype, rng, n):
    m = get(mtype)
    for _ in range(n):
        fixed, bounds = {}, {}
        if rng.random() < 0.3:
            fixed["crank"] = float(rng.uniform(0.2, 2))
        if rng.random() < 0.2:
            fixed["coupler"] = float(rng.uniform(0.5, 4))
        if rng.random() < 0.3 and mtype == "crank_rocker_slider":
            fixed["slider_height"] = float(rng.uniform(0, 2))
        if rng.random() < 0.3:
            bounds["ground"] = (float(rng.uniform(0.1, 1)), float(rng.uniform(1, 5)))
        spec = Spec(mtype, fixed, bounds)
        bound = 0.0 if rng.random() < 0.3 else float(rng.uniform(5, 50))
        objective = ("min_size", "max_transmission_angle")[int(rng.integers(2))]
        t = Targets(float(rng.uniform(1.1, 3)), 1.0, bound, objective, math.inf)
        for parts in variants(m, spec):
            names = relevant(m, parts)
            kept = {k: v for k, v in fixed.items() if k in names}
            yield build_problem(m, parts, names, kept, spec, t)


@pytest.mark.parametrize("mtype", sorted(ROLES))
def test_compiled_construction_matches_numpy(mtype):
    rng = np.random.default_rng(7)
    checked = {"valid": 0, "feasible": 0, "no rod": 0}
    for p in problems(mtype, rng, 80):
        try:
            fb = FourBar(p, ROLES[mtype])
        except Unreachable:  # fixed parts the construction refuses
            continue
        for sigma in (1, -1):
            wide = rng.random() < 0.2
            psi = rng.uniform(0, math.pi, 12) if wide else rng.uniform(*fb.psi, 12)
            lam = 1 + np.exp(rng.uniform(-9, 6, 12))
            got = fb.evaluate(sigma, psi, lam)  # a few points: compiled
            with np.errstate(all="ignore"):
                want = fb._evaluate(sigma, psi, lam)  # numpy
            np.testing.assert_array_equal(got["valid"], want["valid"])
            v = want["valid"]
            np.testing.assert_array_equal(got["feasible"][v], want["feasible"][v])
            for key in KEYS:
                a = np.broadcast_to(got[key], psi.shape)[v]
                b = np.broadcast_to(want[key], psi.shape)[v]
                np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-13, err_msg=key)
            for a, b in zip(got["rho"], want["rho"], strict=True):
                a, b = (np.broadcast_to(x, psi.shape)[v] for x in (a, b))
                np.testing.assert_allclose(a, b, rtol=1e-12)
            checked["valid"] += int(v.sum())
            checked["feasible"] += int(want["feasible"].sum())
            checked["no rod"] += int((v & np.isnan(np.broadcast_to(want["l"], v.shape))).sum())
    if mtype == "drag_link_slider":  # its rod always fits: on the line, any length reaches
        del checked["no rod"]
    assert min(checked.values()) > 20, checked  # every case was met


@pytest.mark.parametrize("mtype", sorted(ROLES))
def test_newton_derivatives_match_differences_of_numpy(mtype):
    """Newton's exact local model (the compiled Taylor function, in (ψ, u), λ = 1 + e^u)
    against central differences of the numpy evaluation, at points where two step sizes agree
    (away from the kinks of a max or a bound)."""
    rng = np.random.default_rng(11)
    checked = 0

    def numpy_rows(fb, sigma, x):
        with np.errstate(all="ignore"):
            e = fb._evaluate(sigma, np.array([x[0]]), 1 + np.exp(np.array([x[1]])))
        return np.array([float(np.asarray(e["size"]).ravel()[0]),
                         float(np.asarray(e["f"]).ravel()[0])])  # fmt: skip

    def differences(fb, sigma, x, h):
        grad, hess = np.zeros((2, 2)), np.zeros((2, 2, 2))
        at = {}
        for i in (-1, 0, 1):
            for j in (-1, 0, 1):
                at[i, j] = numpy_rows(fb, sigma, x + h * np.array([i, j]))
        grad[:, 0] = (at[1, 0] - at[-1, 0]) / (2 * h)
        grad[:, 1] = (at[0, 1] - at[0, -1]) / (2 * h)
        hess[:, 0, 0] = (at[1, 0] - 2 * at[0, 0] + at[-1, 0]) / h**2
        hess[:, 1, 1] = (at[0, 1] - 2 * at[0, 0] + at[0, -1]) / h**2
        hess[:, 0, 1] = hess[:, 1, 0] = (at[1, 1] - at[1, -1] - at[-1, 1] + at[-1, -1]) / (4 * h**2)
        return grad, hess

    for p in problems(mtype, rng, 60):
        try:
            fb = FourBar(p, ROLES[mtype])
        except Unreachable:
            continue
        if fb.ratios:  # with ratios held Newton differences the numpy evaluation itself
            continue
        for sigma in (1, -1):
            local = fb._rows(sigma, "size", 0.5, True, None)
            for _ in range(6):
                x = np.array([rng.uniform(*fb.psi), rng.uniform(-4, 3)])
                t = local(x.tolist())
                if t is None:
                    continue
                (size, f_c), grads, hess = t
                np.testing.assert_allclose([size, f_c + 0.5], numpy_rows(fb, sigma, x), rtol=1e-11)
                g1, h1 = differences(fb, sigma, x, 1e-4)
                g2, h2 = differences(fb, sigma, x, 5e-5)
                if not (np.allclose(g1, g2, rtol=1e-6, atol=1e-9)
                        and np.allclose(h1, h2, rtol=1e-3, atol=1e-6)):  # fmt: skip
                    continue  # a kink within the stencil
                np.testing.assert_allclose(grads, g2, rtol=1e-6, atol=1e-8)
                np.testing.assert_allclose(hess, h2, rtol=1e-3, atol=1e-5)
                checked += 1
    assert checked > 40, checked
