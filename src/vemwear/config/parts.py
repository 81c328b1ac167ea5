"""The boundary parts of a configuration and what each does.

``[boundary]`` names where the clamped, traction, free and contact parts are and holds
``[[boundary.displacement]]`` and ``[[boundary.traction]]`` tables; ``[contact]`` (one
part) or ``[[contact]]`` tables (several, each with ``on``) hold the contact data. Each
part gets a name (its key, the ``name`` of its table, or ``displacement1``, ...); a
selector may also name a part of a mesh file (a gmsh physical group). :func:`roles`
collects the parts with their selectors and data; the mesh is tagged with these names,
and :class:`~vemwear.simulate.Problem` receives the roles.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..contact import ContactPart, LinearCompliance, TableCompliance
from ..simulate import Prescribed, RigidPart
from . import schema as s
from .errors import ConfigError, at
from .expr import Expression

__all__ = ["ComponentExpression", "Roles", "contact_law", "contact_parts", "roles"]


class ComponentExpression:
    """A prescribed displacement component as an expression in ``x, y, z, t``:
    ``f(points, t)`` -> (n,) values of the (n, 2) or (n, 3) points (``z = 0`` in 2D);
    ``__name__`` is its text."""

    def __init__(self, expr: Expression) -> None:
        self.expr, self.__name__ = expr, expr.text

    def __call__(self, x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        X = np.asarray(x, dtype=float)
        P = X.reshape(-1, 3 if X.ndim == 2 and X.shape[1] == 3 else 2)
        z = P[:, 2] if P.shape[1] == 3 else np.zeros(len(P))
        env = {"x": P[:, 0], "y": P[:, 1], "z": z, "t": np.full(len(P), float(t))}
        return np.asarray(self.expr(**env), dtype=float)


def contact_law(law: Any) -> LinearCompliance | TableCompliance:
    """The compliance law of a contact table."""
    if isinstance(law, s.LinearLaw):
        return LinearCompliance(law.c)
    return TableCompliance(tuple(law.r), tuple(law.p))


@dataclass
class Roles:
    """The parts of a configuration.

    Attributes
    ----------
    selectors : dict
        ``{part name: selector}`` for :func:`vemwear.mesh.select_parts` (empty when the
        parts are those of a mesh file).
    where : dict
        ``{part name: key path}`` for messages.
    clamped : tuple of str
    tractions : dict
        ``{part name: (f2 value, raw f2)}`` of the traction tables (empty: the paper's
        single ``traction`` part with ``[loads] f2``).
    displacement : list of Prescribed
    contacts : list of (name, Contact model, raw table, key path)
    """

    selectors: dict[str, Any] = field(default_factory=dict)
    where: dict[str, str] = field(default_factory=dict)
    clamped: tuple[str, ...] = ("clamped",)
    tractions: dict[str, tuple[Any, Any]] = field(default_factory=dict)
    displacement: list[Prescribed] = field(default_factory=list)
    contacts: list[tuple[str, s.Contact, dict[str, Any], str]] = field(default_factory=list)
    rigid: list[RigidPart] = field(default_factory=list)

    def add(self, src: str, name: str, selector: Any, path: str) -> None:
        if name in self.selectors:
            raise ConfigError(
                f"{src}: {path}: the part name {name!r} is taken by {self.where[name]}; "
                "give the parts different names"
            )
        self.selectors[name] = selector
        self.where[name] = path


def _component(v: Any) -> Any:
    return ComponentExpression(v) if isinstance(v, Expression) else v


class TimeExpression:
    """A rigid part's force or translation component as an expression in ``t``."""

    def __init__(self, expr: Expression) -> None:
        self.expr, self.__name__ = expr, expr.text

    def __call__(self, t: float) -> float:
        return float(np.asarray(self.expr(t=np.array([float(t)]))).ravel()[0])


def _time(v: Any) -> Any:
    return TimeExpression(v) if isinstance(v, Expression) else v


def _rigid_part(src: str, name: str, path: str, rp: s.RigidPartTable) -> RigidPart:
    """The library's :class:`RigidPart` of a ``[[boundary.rigid]]`` table."""
    if rp.moment is not None and rp.rotation == "fixed":
        raise ConfigError(
            f"{src}: {path}: moment is for rotation = 'free' (a part whose rotation is fixed "
            "takes the moment as a reaction)"
        )
    if isinstance(rp.rotation, list) and len(rp.rotation) != 3:
        raise ConfigError(
            f"{src}: {path}: rotation is 'fixed', 'free' or one of them per axis in 3D "
            f"(3 components, not {len(rp.rotation)})"
        )
    moment = rp.moment if isinstance(rp.moment, list) else [rp.moment]
    if isinstance(rp.moment, list) and len(rp.moment) != 3:
        raise ConfigError(
            f"{src}: {path}: moment is one number in 2D (M_z) or [M_x, M_y, M_z] in 3D, "
            f"not {len(rp.moment)} components"
        )
    keys = (rp.fx, rp.fy, rp.fz)
    if rp.force is not None and any(k is not None for k in keys):
        raise ConfigError(f"{src}: {path}: give the force as force = [...] or as fx, fy, fz")
    force = list(rp.force) if rp.force is not None else list(keys)
    force += [None] * (3 - len(force))
    trans = [rp.ux, rp.uy, rp.uz]
    for c in range(3):
        if force[c] is not None and trans[c] is not None:
            raise ConfigError(
                f"{src}: {path}: component {'xyz'[c]} has both a force and a prescribed "
                f"translation u{'xyz'[c]}; give one"
            )
    return RigidPart(
        name,
        tuple(_time(f) for f in force),
        tuple(_time(u) for u in trans),
        rotation=rp.rotation if isinstance(rp.rotation, str) else tuple(rp.rotation),
        moment=tuple(_time(m) for m in moment) if rp.moment is not None else (),
    )


def roles(src: str, c: s.ConfigFile, raw: Mapping[str, Any]) -> Roles:
    """The parts of a validated configuration (names checked unique, every contact part
    located)."""
    r = Roles()
    b = c.boundary if isinstance(c.boundary, s.Boundary) else None
    rb: Mapping[str, Any] = raw.get("boundary", {}) if b is not None else {}
    several = isinstance(c.contact, list)
    tables = c.contact if isinstance(c.contact, list) else [c.contact]
    raw_tables = raw["contact"] if several else [raw["contact"]]
    if b is not None:
        r.clamped = ("clamped",) if b.clamped is not None else ()
        if b.clamped is not None:
            r.add(src, "clamped", b.clamped, "[boundary] clamped")
        if b.free is not None:
            r.add(src, "free", b.free, "[boundary] free")
        if isinstance(b.traction, list) and all(isinstance(t, s.TractionPart) for t in b.traction):
            if "f2" in raw.get("loads", {}):
                raise ConfigError(
                    f"{src}: [loads] f2 is the traction of [boundary] traction; with "
                    "[[boundary.traction]] tables give f2 in each table"
                )
            for i, tp in enumerate(b.traction):
                name = tp.name or f"traction{i + 1}"
                path = f"[[boundary.traction]] {i + 1}"
                r.add(src, name, tp.on, path)
                r.tractions[name] = (tp.f2, rb["traction"][i]["f2"])
        elif b.traction is not None:
            r.add(src, "traction", b.traction, "[boundary] traction")
        for i, dp in enumerate(b.displacement or []):
            name = dp.name or f"displacement{i + 1}"
            path = f"[[boundary.displacement]] {i + 1}"
            r.add(src, name, dp.on, path)
            if dp.ux is None and dp.uy is None and dp.uz is None:
                raise ConfigError(f"{src}: {path}: give ux, uy or both")
            r.displacement.append(
                Prescribed(name, _component(dp.ux), _component(dp.uy), _component(dp.uz))
            )
        for i, rp in enumerate(b.rigid or []):
            name = rp.name or f"rigid{i + 1}"
            path = f"[[boundary.rigid]] {i + 1}"
            r.add(src, name, rp.on, path)
            r.rigid.append(_rigid_part(src, name, path, rp))
    for i, (ct, rt) in enumerate(zip(tables, raw_tables, strict=True)):
        path = f"[[contact]] {i + 1}" if several else "[contact]"
        name = ct.name or (f"contact{i + 1}" if several else "contact")
        on = ct.on
        if not several and b is not None and b.contact is not None:
            if on is not None:
                raise ConfigError(
                    f"{src}: [contact] on and [boundary] contact both say where the contact "
                    "part is; keep one"
                )
            on = b.contact
            path = "[boundary] contact"
        if on is not None:
            r.add(src, name, on, path)
        elif b is not None or several:
            raise ConfigError(
                f"{src}: {path}: where is the contact part? give 'on' (a side, a segment or "
                "a part of the mesh file)" + ("" if several else " or [boundary] contact")
            )
        r.contacts.append((name, ct, rt, "[contact]" if not several else path))
    # the parts in the order of the keys of [boundary] (the first of two overlapping
    # parts is named first in messages), the contact tables last
    keys = list(rb)

    def position(name: str) -> int:
        m = re.match(r"\[+boundary\]*[ .](\w+)", r.where[name])
        return keys.index(m.group(1)) if m and m.group(1) in keys else len(keys)

    r.selectors = dict(sorted(r.selectors.items(), key=lambda kv: position(kv[0])))
    return r


def contact_parts(src: str, r: Roles, data: Any, velocity: Any) -> tuple[ContactPart, ...]:
    """The :class:`ContactPart` of every contact table (``data`` and ``velocity`` turn
    schema values into the library's)."""
    out = []
    for name, ct, rt, path in r.contacts:
        with at(src, path, rt, key="p"):
            law = contact_law(ct.p)
        out.append(
            ContactPart(
                name,
                law,
                data(ct.g, None, None),
                data(ct.mu, None, None),
                data(ct.kappa, None, None),
                velocity(ct.v_star, rt["v_star"]),
                data(ct.gap, None, None),
                friction_on=ct.friction_on,
                wear_on=ct.wear_on,
            )
        )
    return tuple(out)
