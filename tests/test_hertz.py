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
