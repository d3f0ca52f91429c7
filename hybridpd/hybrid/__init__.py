"""The generic hybrid-automaton layer: LTI flows, affine guards and resets, event location.

Nothing here knows about impact pairs; :mod:`hybridpd.pair` and :mod:`hybridpd.mechanics`
are instances built on it.

Modules: :mod:`~hybridpd.hybrid.events` (exact LTI flows and guaranteed event location),
:mod:`~hybridpd.hybrid.automaton` (:class:`~hybridpd.hybrid.automaton.HybridAutomaton`, its
semantics, and every public name of the three modules it is built from:
:mod:`~hybridpd.hybrid.modes`, :mod:`~hybridpd.hybrid.trajectory` and the numba jump loop
:mod:`~hybridpd.hybrid._kernel`), :mod:`~hybridpd.hybrid.samples` (sample models).
"""
