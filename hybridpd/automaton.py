"""Deprecated: this module moved to :mod:`hybridpd.hybrid.automaton` and goes in hybridpd 0.3.0.

Kept for one release so that code written for earlier versions runs; importing it warns with
``DeprecationWarning``. Import from ``hybridpd.hybrid.automaton`` (or the flat ``hybridpd`` namespace) instead.
"""
from hybridpd._deprecated import moved_module

__getattr__, __dir__ = moved_module(__name__)
