"""Deprecated: :func:`save_branch` and :func:`load_branch` moved to
:mod:`hybridpd.analysis.continuation.events` (with the :class:`Branch` they read and write) and
this module goes in hybridpd 0.3.0. Use ``hybridpd.load_branch`` or :meth:`Branch.save`.
"""
from hybridpd._deprecated import moved_module

__getattr__, __dir__ = moved_module(__name__)
