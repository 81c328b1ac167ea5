"""Hertz contact under load control against the closed forms (docs/method.md section 8,
``vemwear example hertz``): the 2D line contact at h <= a/32 and the 3D sphere."""

from __future__ import annotations

import numpy as np
import pytest

from vemwear import simulate
from vemwear.paper.hertz import line_contact, measure, sphere

A = 0.05


@pytest.fixture(scope="module")
def lines() -> dict[int, dict[str, float]]:
    return {lv: measure(simulate(line_contact(A, lv), "newton"), A) for lv in (5, 8)}


def test_line_contact_within_one_percent_at_h_a_over_32(lines: dict[int, dict]) -> None:
    fine = lines[8]
    assert A / fine["h"] >= 32
    assert abs(fine["a_err"]) < 0.01 and abs(fine["p0_err"]) < 0.01
    assert fine["l2_err"] < 0.02 and abs(fine["load_err"]) < 1e-12
    # the profile's error decreases under refinement (2.6 % at h = a/6, 0.54 % at a/51)
    assert fine["l2_err"] < 0.3 * lines[5]["l2_err"]


@pytest.mark.slow
def test_sphere_within_two_and_three_percent() -> None:
    coarse = measure(simulate(sphere(A, 6), "newton"), A)
    fine = measure(simulate(sphere(A, 18), "newton"), A)
    assert abs(fine["a_err"]) < 0.02 and abs(fine["p0_err"]) < 0.03
    assert abs(fine["a_err"]) < 0.5 * abs(coarse["a_err"])
    assert abs(fine["p0_err"]) < 0.5 * abs(coarse["p0_err"])


def test_the_solvers_agree_on_a_hertz_contact() -> None:
    pr = line_contact(A, 3, n=16)
    a, b = simulate(pr, "newton"), simulate(pr, "newton-full")
    assert np.abs(a.u - b.u).max() <= 1e-9 * np.abs(a.u).max()
    assert np.abs(a.p_rigid - b.p_rigid).max() <= 1e-9 * a.p_rigid.max()


def test_a_stiff_sphere_on_a_winkler_layer() -> None:
    """A sphere much stiffer than its linear soft layer p(r) = c r_+ (Winkler): the
    pressure is c (delta - r^2/(2R)) with a^2 = 2 R delta and P = pi c R delta^2."""
    import dataclasses

    from vemwear import LinearCompliance, Material
    from vemwear.paper.hertz import ETA, LAM, R
    from vemwear.simulate import RigidPart

    c, delta = 1.0, A * A / (2 * R)
    P = np.pi * c * R * delta**2
    base = sphere(A, 12)
    pr = dataclasses.replace(
        base,
        material=Material(LAM * 1e4, ETA * 1e4),
        p=LinearCompliance(c),
        g=1.0,
        rigid=(RigidPart("holder", force=(None, None, -P / 4)),),
    )
    res = simulate(pr, "newton")
    X = res.contact_points
    r2 = X[:, 0] ** 2 + X[:, 1] ** 2
    exact = c * np.maximum(delta - r2 / (2 * R), 0.0)
    p = res.p_soft[-1]
    assert np.abs(p - exact).max() <= 0.01 * c * delta
    w = pr.contact.weights
    a_h = np.sqrt(3 * np.sum(w * p * r2) / np.sum(w * p))  # p ~ 1 - r^2/a^2
    assert abs(a_h / A - 1) < 0.01


def test_a_worn_sphere_presses_uniformly_over_its_scar() -> None:
    """A stiff sphere sliding under a constant load on a Winkler layer that wears: once
    the worn depth is many times the elastic approach (14 times here), the pressure is
    uniform over the scar and the scar's radius follows from the worn volume,
    V = pi a^4 / (4 R) (a cap of depth a^2 / (2R))."""
    import dataclasses

    from vemwear import LinearCompliance, Material, TimeGrid
    from vemwear.paper.hertz import ETA, LAM, R
    from vemwear.simulate import RigidPart

    c, approach = 1.0, 1.25e-3  # the elastic (layer) approach under P at the start
    P = np.pi * c * R * approach**2
    pr = dataclasses.replace(
        sphere(0.15, 8),
        material=Material(LAM * 1e2, ETA * 1e2),
        p=LinearCompliance(c),
        g=1.0,
        kappa=200.0,
        time=TimeGrid.uniform(1.0, 256),
        rigid=(RigidPart("holder", force=(None, None, -P / 4)),),
    )
    res = simulate(pr, "newton", store="final")
    X, w = res.contact_points, pr.contact.weights
    r = np.hypot(X[:, 0], X[:, 1])
    wear, p = res.wear[-1], res.p_soft[-1]
    assert wear.max() > 10 * approach
    a_volume = (4 * R * 4 * np.sum(w * wear) / np.pi) ** 0.25  # the quarter's volume x 4
    inner = p[r < 0.8 * a_volume]
    assert inner.max() / inner.min() - 1 < 0.02  # uniform over the scar
    a_pressure = np.sqrt(P / (np.pi * inner.mean()))  # P = pi a^2 p
    assert abs(a_pressure / a_volume - 1) < 0.02
