"""What the modes and guards of a mechanical automaton mean, read from their names.

:class:`ModeInfo` (the held contacts and the compliant configuration of a mode) and
:class:`GuardInfo` (an impact, release, compliant switch or sample of which contact, wall or
controller), and the lazy tables :class:`~hybridpd.mechanics.automaton.MechanicalAutomaton`
exposes as ``modes``, ``guards``, ``impact_resets`` and ``plastic_resets``: nothing is built
to answer them.
"""
from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass

__all__ = ["GuardInfo", "ModeInfo"]

_GUARD_RE = re.compile(r"\A(contact|release|enter|leave)(\d+)([+-])\Z")
_GUARD_KIND = {"contact": "impact", "release": "release", "enter": "enter", "leave": "leave"}


@dataclass(frozen=True)
class ModeInfo:
    """What a mode means: ``config[j]`` in ``{-1, 0, +1}`` per contact (compliant ones only
    non-zero), ``stick``: tuple of the held ``(k, wall)`` (empty: free)."""

    name: str
    config: tuple
    stick: tuple


@dataclass(frozen=True)
class GuardInfo:
    """What a guard means.

    ``kind`` is ``'impact'``, ``'release'``, ``'enter'``, ``'leave'`` or ``'sample'``;
    ``contact`` the 0-based contact index (``-1`` for ``'sample'``); ``wall`` ``+1`` at ``hi``,
    ``-1`` at ``lo`` (0 for ``'sample'``); ``controller`` the index of the controller a
    ``'sample'`` guard samples (``-1`` for the other kinds).
    """

    kind: str
    contact: int
    wall: int
    controller: int = -1

    def __repr__(self):
        extra = f", controller={self.controller}" if self.kind == "sample" else ""
        return (f"GuardInfo(kind={self.kind!r}, contact={self.contact}, wall={self.wall}"
                f"{extra})")


class _ModeTable(Mapping):
    """Mode name -> :class:`ModeInfo`, parsed from the name (no mode is built)."""

    def __init__(self, ha, parse):
        self._ha, self._parse = ha, parse     # parse(name) -> (config, stick), or ValueError
        self._cache = {}

    def __getitem__(self, name):
        info = self._cache.get(name) if isinstance(name, str) else None
        if info is None:
            try:
                config, stick = self._parse(name)
            except ValueError:
                raise KeyError(name) from None
            info = self._cache[name] = ModeInfo(name, config, stick)
        return info

    def __iter__(self):
        return iter(list(self._ha._names))

    def __len__(self):
        return len(self._ha._names)

    def __contains__(self, name):
        try:
            self[name]
        except KeyError:
            return False
        return True


class _GuardTable(Mapping):
    """``(mode, guard)`` -> :class:`GuardInfo`, parsed from the guard name."""

    def __init__(self, ha, sample_guards):
        self._ha = ha
        self._samples = dict(sample_guards)    # sampling guard name -> controller index
        self._cache = {}   # guard name -> GuardInfo: a trajectory asks once per jump

    def __getitem__(self, key):
        try:
            _, gname = key
        except (TypeError, ValueError):
            raise KeyError(key) from None
        info = self._cache.get(gname)
        if info is not None:
            return info
        if gname in self._samples:
            info = GuardInfo("sample", -1, 0, self._samples[gname])
        else:
            m = _GUARD_RE.match(str(gname))
            if m is None:
                raise KeyError(key)
            info = GuardInfo(_GUARD_KIND[m.group(1)], int(m.group(2)),
                             1 if m.group(3) == "+" else -1)
        self._cache[gname] = info
        return info

    def _items(self):
        out = []
        for i, name in enumerate(self._ha._names):
            mode = self._ha._built[i]
            if mode is not None:
                out.extend((name, g.name) for g in mode.guards)
        return out

    def __iter__(self):
        return iter(self._items())

    def __len__(self):
        return len(self._items())


class _ResetTable(Mapping):
    """``(k, wall)`` -> ``(R, r)`` of a rigid contact, computed on demand."""

    def __init__(self, geo, which):
        self._geo, self._which = geo, which
        self._keys = [(k, w) for k, c in enumerate(geo.contacts) if c.rigid
                      for w, _ in c.bounds]

    def __getitem__(self, key):
        if key not in self._keys:
            raise KeyError(key)
        k, w = key
        if self._which == "impact":
            return self._geo.impact(k, ())
        return self._geo.projection(((k, w),))

    def __iter__(self):
        return iter(self._keys)

    def __len__(self):
        return len(self._keys)
