"""Deprecated: this module moved to :mod:`hybridpd.analysis.design` and goes in hybridpd 0.3.0.

Kept for one release so that code written for earlier versions runs; importing it warns with
``DeprecationWarning``. Import from ``hybridpd.analysis.design`` (or the flat ``hybridpd``
namespace) instead.
"""
import sys
import types

from hybridpd._deprecated import moved_module

__getattr__, __dir__ = moved_module(__name__)


class _DesignShim(types.ModuleType):
    """Once imported, this module is bound to ``hybridpd.design``, the name of the flat
    namespace's :func:`~hybridpd.analysis.design.design`; calling it keeps that name working."""

    def __call__(self, *args, **kwargs):
        return __getattr__("design")(*args, **kwargs)


sys.modules[__name__].__class__ = _DesignShim
