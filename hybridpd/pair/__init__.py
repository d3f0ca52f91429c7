"""The paper's impact pair: its automaton instance and its named fast paths.

``impactpair`` is the pair written on the generic automaton (the general path);
``symbolic`` holds the SymPy closed forms (flows, existence, Jacobian blocks) and ``batch``
the compiled closed-form engine. Both fast paths are checked against the general path in the
tests. ``naive`` is the plain ``solve_ivp`` loop kept as an independent reference.
``certified`` proves the symmetric orbit's class on boxes of parameters, in the interval
arithmetic of ``intervals`` and ``centred`` on the closed forms of ``interval_kernels``
(the proofs themselves in ``proofs``; with the record of what decided each box, adaptive
subdivision and the sharper viability test in ``prooftree``), confirms every proved cell in
python-flint's ``arb`` (``arbcheck``) and writes and re-proves certificates (``certificate``).
"""
