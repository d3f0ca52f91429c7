"""The generic hybrid-automaton layer: LTI flows, affine guards and resets, event location.

Nothing here knows about impact pairs; :mod:`hybridpd.pair` and :mod:`hybridpd.mechanics`
are instances built on it.
"""
