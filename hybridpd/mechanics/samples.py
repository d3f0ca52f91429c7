"""Sample mechanical systems with many contacts (for tests, benchmarks and examples).

:func:`mass_chain`: ``N`` masses in a line, neighbours joined by a spring-damper in parallel
with a rigid clearance (``m = N - 1`` contacts), a PD loop on the first mass tracking a sine:
a drivetrain with a clearance per stage, or an impact damper with many cells.
:func:`chain_model_text` writes the same system as a model file (TOML text).
"""
from __future__ import annotations

import numpy as np

from hybridpd.mechanics.automaton import MechanicalAutomaton, build_automaton
from hybridpd.mechanics.contacts import Contact
from hybridpd.mechanics.loop import Reference, mechanical_loop
from hybridpd.mechanics.system import MechanicalSystem

__all__ = ["chain_matrices", "chain_model_text", "mass_chain"]


def chain_matrices(n_masses: int, stiffness: float = 20.0, damping: float = 0.1):
    """``(M, C, K, B)`` of the chain: unit masses, neighbour springs and dampers, input on
    mass 0 (shapes ``(N, N)`` and ``(N,)``)."""
    N = int(n_masses)
    if N < 2:
        raise ValueError(f"n_masses must be >= 2, got {n_masses!r}")
    K = np.zeros((N, N))
    C = np.zeros((N, N))
    for i in range(N - 1):
        for A, val in ((K, stiffness), (C, damping)):
            A[i, i] += val
            A[i + 1, i + 1] += val
            A[i, i + 1] -= val
            A[i + 1, i] -= val
    B = np.zeros(N)
    B[0] = 1.0
    return np.eye(N), C, K, B


def mass_chain(n_masses: int, clearance: float = 0.05, restitution: float = 0.8,
               stiffness: float = 20.0, damping: float = 0.1, kp: float = 50.0,
               kv: float = 5.0, amplitude: float = 1.0, omega: float = 3.0
               ) -> MechanicalAutomaton:
    """A chain of unit masses with a clearance ``|q_i - q_{i+1}| <= clearance`` per link.

    Parameters
    ----------
    n_masses : int
        ``N >= 2`` (``N - 1`` rigid contacts).
    clearance : float
        Half-clearance of every link (length units, ``> 0``).
    restitution : float
        Newton's ``e`` of every contact, in ``[0, 1]``.
    stiffness, damping : float
        Link spring (force per length) and damper (force per velocity).
    kp, kv : float
        PD gains on mass 0.
    amplitude, omega : float
        Reference ``amplitude cos(omega t)`` (length units, rad per time unit).

    Returns
    -------
    MechanicalAutomaton
        Only its free mode is built (the others on demand).

    Examples
    --------
    >>> from hybridpd.mechanics.samples import mass_chain
    >>> ma = mass_chain(31)
    >>> len(ma.contacts), ma.automaton.n_built
    (30, 1)
    """
    if not clearance > 0:
        raise ValueError(f"clearance must be > 0, got {clearance!r}")
    M, C, K, B = chain_matrices(n_masses, stiffness, damping)
    N = M.shape[0]
    s = MechanicalSystem([f"m{i}" for i in range(N)], M, C, K, B)
    loop = mechanical_loop(s, (kp, kv), Reference.sine(amplitude, omega, 0.0), "m0")
    eye = np.eye(N)
    return build_automaton(loop, [Contact(eye[i] - eye[i + 1], -clearance, clearance,
                                          restitution=restitution, name=f"link{i}")
                                  for i in range(N - 1)])


def chain_model_text(n_masses: int, clearance: float = 0.05, restitution: float = 0.8,
                     stiffness: float = 20.0, damping: float = 0.1, kp: float = 50.0,
                     kv: float = 5.0, amplitude: float = 1.0, omega: float = 3.0) -> str:
    """The chain of :func:`mass_chain` as a model file (TOML text, for ``--model``).

    Parameters are those of :func:`mass_chain`; DOFs ``m0 ... m{N-1}``, contacts
    ``link0 ...`` (``lo = -clearance``, ``hi = clearance`` on ``m_i - m_{i+1}``).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from hybridpd.mechanics.modelfile import load_model
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = pathlib.Path(d) / "chain.toml"
    ...     _ = path.write_text(chain_model_text(4))
    ...     model = load_model(path)
    >>> len(model.automaton.contacts), model.system.n
    (3, 4)
    """
    if not clearance > 0:
        raise ValueError(f"clearance must be > 0, got {clearance!r}")
    if not 0.0 <= restitution <= 1.0:
        raise ValueError(f"restitution must be in [0, 1], got {restitution!r}")
    M, C, K, B = chain_matrices(n_masses, stiffness, damping)
    N = M.shape[0]

    def mat(A):
        return "[" + ",\n  ".join("[" + ", ".join(f"{float(x)!r}" for x in row) + "]"
                                    for row in A) + "]"

    lines = ["[system]", "dofs = [" + ", ".join(f'"m{i}"' for i in range(N)) + "]",
             "masses = [" + ", ".join("1.0" for _ in range(N)) + "]",
             f"damping = {mat(C)}", f"stiffness = {mat(K)}",
             "input = [" + ", ".join(f"{x:.1f}" for x in B) + "]", ""]
    for i in range(N - 1):
        lines += ["[[contact]]", f'name = "link{i}"', f'between = ["m{i}", "m{i + 1}"]',
                  f"lo = {-float(clearance)!r}", f"hi = {float(clearance)!r}",
                  f"restitution = {float(restitution)!r}", ""]
    lines += ["[controller]", 'type = "pd"', f"kp = {float(kp)!r}", f"kv = {float(kv)!r}",
              'measure = "m0"', "", "[reference]", 'type = "sine"',
              f"amplitude = {float(amplitude)!r}", f"omega = {float(omega)!r}", ""]
    return "\n".join(lines)
