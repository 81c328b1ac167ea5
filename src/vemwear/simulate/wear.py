"""The wear law, discretized: the wear rate ``alpha`` (2.2) and the explicit update of
the wear (3.22). Every computation of either goes through these two functions (the time
loop, the state of a resumed run, the overshoot warning), so that they give the same
numbers, bitwise."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["wear_rate", "wear_update"]


def wear_rate(kappa: Any, speed: Any) -> Any:
    """``alpha = kappa |v*_tau|`` (2.2): the wear per unit pressure and unit time.

    Parameters
    ----------
    kappa : float or ndarray
        The wear coefficients (at the contact nodes).
    speed : ndarray
        The tangential speed of the foundation ``|v*_tau|`` there (any shape that
        broadcasts with ``kappa``, e.g. (levels, nodes)).
    """
    return kappa * speed


def wear_update(w: Any, k: float, alpha: Any, pressure: Any) -> Any:
    """``w^{n+1} = w^n + k_n alpha(t_n) P^n`` (3.22), the left rectangle rule.

    Parameters
    ----------
    w : ndarray
        The wear ``w^n`` at the contact nodes.
    k : float
        The time step ``k_n = t_{n+1} - t_n``.
    alpha : ndarray
        The wear rate at ``t_n`` (:func:`wear_rate`).
    pressure : ndarray
        The pressure that wears: ``p_soft`` of level n (plus ``p_rigid`` where the whole
        pressure wears).

    Returns
    -------
    ndarray
        ``w^{n+1}``; an overflow gives ``inf`` without a warning (the caller checks).
    """
    with np.errstate(all="ignore"):
        return w + k * alpha * pressure
