"""Signals of a run: SIGTERM and SIGHUP stop it like Ctrl-C; saving is not abandoned lightly.

:func:`signals_as_interrupts` turns SIGTERM (a ``kill``, a batch system's time limit)
and SIGHUP (a closed terminal) into :class:`Terminated`, a ``KeyboardInterrupt``, so
that a run stops through the same path as after Ctrl-C and keeps its finished levels.
The first signal prints a line (``vemwear: interrupted (Ctrl-C); stopping``) and stops
the run (at once, or at the end of a checkpoint being written: :func:`saving` marks
such sections). A second signal does not abandon the save of the finished levels that
follows: a line says so (``... please wait (once more to abandon the save)``); only a
third one abandons it.

The handler never raises inside a finalizer (``weakref.finalize``, ``__del__``): Python
prints and swallows an exception raised there, and the run would go on. A signal that
lands in one is kept as a flag; a timer (``SIGALRM``, every 50 ms) raises it at the
first instant outside, and :func:`check_stop` raises it at the safe points that call
it. So a run stops within a fraction of a second of the signal at any instant (longer
only while a single call into compiled code does not return).
"""

from __future__ import annotations

import signal
import sys
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from types import FrameType
from typing import Any

__all__ = [
    "Terminated",
    "check_stop",
    "saving",
    "signals_as_interrupts",
    "stop_reason",
    "stop_signal",
]

_NAMES = {"SIGTERM": "terminated (SIGTERM)", "SIGHUP": "hung up (SIGHUP)"}


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP, handled like Ctrl-C; ``signame`` says which."""

    def __init__(self, signame: str = "SIGTERM") -> None:
        super().__init__(signame)
        self.signame = signame


class _State:
    depth = 0  # nesting of saving()
    pending: BaseException | None = None  # the stop signal received while saving
    stopping = False  # a signal has stopped the run: its levels are being saved
    count = 0  # signals received since
    deferred: BaseException | None = None  # a signal that landed in a finalizer, to raise
    signal: BaseException | None = None  # the first stop signal received


def stop_signal(exc: BaseException) -> KeyboardInterrupt | None:
    """The stop signal behind ``exc``: ``exc`` itself, or the one it was raised while
    handling (a library that fails as it unwinds from the signal, such as a zip file
    closed while its member's handle is still open), else None.

    A compiled library may also replace the signal's exception by its own, with no
    chain (matplotlib's C++ path code: ``ValueError: Invalid bounding box``): so any
    exception raised after a stop signal within :func:`signals_as_interrupts` counts as
    the stop (it is marked as such when it leaves the context)."""
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return e
        marked = getattr(e, "vemwear_stopped_by", None)
        if isinstance(marked, KeyboardInterrupt):
            return marked
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    sig = _State.signal
    return sig if isinstance(sig, KeyboardInterrupt) else None


def stop_reason(exc: BaseException) -> str | None:
    """``"interrupted (Ctrl-C)"``, ``"terminated (SIGTERM)"``, ... for a stop by a signal
    (:func:`stop_signal`), else None."""
    sig = stop_signal(exc)
    if isinstance(sig, Terminated):
        return _NAMES.get(sig.signame, f"stopped ({sig.signame})")
    if sig is not None:
        return "interrupted (Ctrl-C)"
    return None


def _say(line: str) -> None:
    try:  # after SIGHUP the terminal may be gone
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


#: Code that must never see an exception from a signal handler: Python swallows it.
_FINALIZERS = frozenset({"__del__", "_exitfunc"})


def _in_finalizer(frame: FrameType | None) -> bool:
    """Whether ``frame`` runs inside a finalizer (``__del__``, ``weakref.finalize``)."""
    while frame is not None:
        code = frame.f_code
        if code.co_name in _FINALIZERS or (
            code.co_name == "__call__" and code.co_filename.endswith("weakref.py")
        ):
            return True
        frame = frame.f_back
    return False


def _raise(exc: BaseException, frame: FrameType | None) -> None:
    """Raise ``exc`` here, or, inside a finalizer, as soon as the finalizer is left."""
    if _in_finalizer(frame):
        _State.deferred = exc
        signal.setitimer(signal.ITIMER_REAL, _RETRY)
        return
    _State.deferred = None
    raise exc


#: Seconds between two tries to raise a signal that landed in a finalizer.
_RETRY = 0.05


def _retry(signum: int, frame: FrameType | None) -> None:
    if _State.deferred is not None:
        _raise(_State.deferred, frame)


def check_stop() -> None:
    """A safe point: raise the stop signal that landed in a finalizer, if any, or one
    that a library swallowed (a stop signal was received, yet the run goes on here)."""
    exc = _State.deferred
    if exc is not None:
        _State.deferred = None
        signal.setitimer(signal.ITIMER_REAL, 0)
        raise exc
    if _State.stopping and _State.depth == 0 and _State.signal is not None:
        raise _State.signal


def _handler(signum: int, frame: FrameType | None) -> None:
    name = signal.Signals(signum).name
    exc: BaseException = KeyboardInterrupt() if name == "SIGINT" else Terminated(name)
    if not _State.stopping:  # the first signal stops the run (after a checkpoint being saved)
        _State.stopping = True
        _State.signal = exc
        _say(f"vemwear: {stop_reason(exc)}; stopping")
        if _State.depth == 0:
            _raise(exc, frame)
            return
        _State.pending = exc
        return
    _State.count += 1
    if _State.count >= 2:  # the second signal during the save abandons it
        _raise(exc, frame)
        return
    _say("vemwear: saving the finished levels; please wait (once more to abandon the save)")


@contextmanager
def signals_as_interrupts() -> Iterator[None]:
    """Install the handlers of SIGINT, SIGTERM and SIGHUP (main thread only), restore after."""
    old: dict[int, Any] = {}
    try:
        for name in ("SIGINT", "SIGTERM", "SIGHUP", "SIGALRM"):
            sig = getattr(signal, name, None)
            if sig is not None:
                old[sig] = signal.signal(sig, _retry if name == "SIGALRM" else _handler)
    except ValueError:  # not the main thread
        pass
    try:
        yield
    except BaseException as exc:
        stop = stop_signal(exc)
        if stop is not None and stop is not exc:  # still the stop once the context is left
            with suppress(AttributeError):
                exc.vemwear_stopped_by = stop  # type: ignore[attr-defined]
        raise
    finally:
        if old:
            signal.setitimer(signal.ITIMER_REAL, 0)
        for sig, h in old.items():
            signal.signal(sig, h)
        _State.stopping, _State.count, _State.pending, _State.deferred = False, 0, None, None
        _State.signal = None


@contextmanager
def saving(reraise: bool = True) -> Iterator[None]:
    """A section that a first signal does not interrupt.

    Parameters
    ----------
    reraise : bool
        Raise the signal received during the section at its end (a periodic
        checkpoint); False when the run is stopping anyway (the final save).
    """
    _State.depth += 1
    try:
        yield
    finally:
        _State.depth -= 1
        if _State.depth == 0:
            pending, _State.pending = _State.pending, None
            if pending is not None and reraise:  # the run stops now
                raise pending
