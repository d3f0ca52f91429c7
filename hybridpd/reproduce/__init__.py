"""Reproduce the paper's results section (Figs 3-7) and settle its conclusions with numbers.

``hybridpd reproduce [--quick | --full] [--out DIR] [--m2 ...] [--x10 X] [--json]`` runs
:func:`reproduce`:

* **The convention study** (:mod:`~hybridpd.reproduce.study`): only ``kp/m2`` and ``kv/m2``
  matter and the paper gives no ``m2``. The intervals of ``m2`` where the orbits at the
  paper's gains exist and are stable (end points are located bifurcation points), and every
  conclusion's verdict against ``m2`` over ``[0.1, 1000]``.
* **Figs 3-7 under each convention** (default ``m2 = 1`` and the ``m2`` chosen by the
  documented rule of :func:`~hybridpd.reproduce.study.choose_m2`), gain boxes scaled by ``m2``,
  and Figs 4-5 once for every ``m2`` in the scaled gains (:mod:`~hybridpd.reproduce.figures`).
* **The conclusions** (:mod:`~hybridpd.reproduce.conclusions`) on existence alone, stability
  alone and both, by the verdict rules of :mod:`~hybridpd.reproduce.rules` (four verdicts,
  two grid resolutions, whole-range trends, one basin window per figure); **the mu and gamma
  studies** (:mod:`~hybridpd.reproduce.params`).
* ``summary.json`` (schema :data:`~hybridpd.reproduce.summary.SCHEMA`) and ``summary.md``.

Every open convention is a field of :class:`Settings`. The package itself is callable:
``hp.reproduce(out, mode="quick")`` runs :func:`reproduce`.

Examples
--------
>>> import hybridpd as hp
>>> s = hp.reproduce.Settings.quick()
>>> s.m2, s.basin
((1.0, 'auto'), (41, 41))
>>> summary = hp.reproduce("reproduce-out", mode="quick", log=None)  # doctest: +SKIP

The last line takes about a minute on two cores and writes the figures, ``summary.md`` and
``summary.json`` into ``reproduce-out/``.
"""
import sys
import types

from hybridpd.reproduce.pipeline import reproduce, run_convention
from hybridpd.reproduce.settings import AUTO, PAPER, Settings
from hybridpd.reproduce.summary import SCHEMA, validate

__all__ = ["AUTO", "PAPER", "SCHEMA", "Settings", "reproduce", "run_convention", "validate"]


class _ReproducePackage(types.ModuleType):
    """This package, callable as :func:`reproduce`.

    ``hybridpd.reproduce`` names both this package and the function that runs it; once the
    package is imported, Python binds the package to that attribute of ``hybridpd``, so the
    package itself answers the call and ``hp.reproduce(...)`` always runs the reproduction.
    """

    def __call__(self, *args, **kwargs):
        return reproduce(*args, **kwargs)


sys.modules[__name__].__class__ = _ReproducePackage
