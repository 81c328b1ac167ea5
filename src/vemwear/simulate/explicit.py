"""When the explicit wear rule (3.22) can overshoot.

The left rectangle rule ``w^{n+1} = w^n + k_n alpha(t_n) p(u_nu^n - w^n)``, with
``alpha = kappa |v*_tau|``, is explicit in the wear: on a node pressed into the soft layer
with a fixed ``u_nu``, the penetration ``r = u_nu - w`` evolves as
``r^{n+1} = r^n - k_n alpha p(r^n)``, which for a law of slope up to ``L_p`` overshoots
(``r`` changes sign: more wear than the layer was penetrated) as soon as
``k_n alpha(t_n) L_p >= 1``. :func:`overshoot` measures that number on the time grid;
the command line warns when it is at least 1 (docs/method.md).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .wear import wear_rate

if TYPE_CHECKING:
    from .problem import Problem

__all__ = ["overshoot", "overshoot_warning"]


def overshoot(problem: Problem) -> tuple[float, int, float]:
    """``(max_n k_n max_a kappa_a |v*_tau(a, t_n)| L_p, the level n, the largest safe step)``.

    The safe step is ``1 / max_n (max_a kappa_a |v*_tau(a, t_n)| L_p)`` (inf if there is
    no wear, 0 if that rate is not finite); ``L_p`` is the Lipschitz constant of the
    node's compliance law. Evaluated for all levels at once (in blocks of levels that
    keep the (levels, nodes) products to about a million numbers).
    """
    t = problem.time.t
    if len(t) < 2:
        return 0.0, 0, float("inf")
    from ..contact import velocity_levels

    kappa = problem.nodal["kappa"]
    cb = problem.contact
    L_p = np.array([float(getattr(pc.p, "lipschitz", 0.0)) for pc in problem.parts])[cb.part]
    if not np.all(np.isfinite(L_p)):
        return 0.0, 0, float("inf")
    # alpha L_p = kappa |v*(t_n) . tau_a| L_p: its largest value over the nodes of every
    # part (each with its own v*), at every level
    rate = np.zeros(len(t) - 1)
    with np.errstate(all="ignore"):
        for i, pc in enumerate(problem.parts):
            sel = np.asarray(cb.part) == i
            tau, k, lp = cb.tangents[sel], kappa[sel], L_p[sel]
            if not tau.size:
                continue
            if pc.velocity.spatial or cb.tangents2 is not None:
                # a field or a v* that turns: |v*_tau| level by level, over the nodes
                P, nu = cb.points[sel], cb.normals[sel]
                for n in range(len(t) - 1):
                    V = pc.velocity.at(P, float(t[n]))
                    V_tau = V - np.sum(V * nu, axis=1)[:, None] * nu
                    r_n = float((wear_rate(k, np.linalg.norm(V_tau, axis=1)) * lp).max())
                    rate[n] = max(rate[n], np.inf if np.isnan(r_n) else r_n)
                continue
            block = max(1, 2**20 // len(tau))
            for a in range(0, len(t) - 1, block):
                b = min(a + block, len(t) - 1)
                V = velocity_levels(pc.velocity, t[a:b])
                r = (wear_rate(k, np.abs(V @ tau.T)) * lp).max(axis=1)
                rate[a:b] = np.maximum(rate[a:b], np.where(np.isnan(r), np.inf, r))
        value = np.diff(t) * rate
    n = int(np.argmax(value))
    top = float(rate.max())
    return float(value[n]), n, (1.0 / top if top > 0 else float("inf"))


def overshoot_warning(problem: Problem) -> str | None:
    """A one-line warning when the explicit wear can overshoot, else None."""
    value, n, safe = overshoot(problem)
    if value < 1.0:
        return None
    t = float(problem.time.t[n])
    advice = (
        f"Use time steps below {safe:.3g}"
        if safe > 0
        else "No time step is safe: kappa |v*| L_p overflows; use data of a sensible scale"
    )
    return (
        f"the explicit wear update can overshoot: k kappa |v*| L_p = {value:.3g} >= 1 at "
        f"level {n} (t = {t:g}); the wear may exceed the penetration and oscillate. {advice}"
    )
