"""Model files: a mechanical system, its contacts, controllers, references and initial state.

The full schema (every key, its type, default and unit, and the discretisation of each
controller type) is the user guide's page "Model files" (``docs/guide/model_files.rst``).
In short (every key is checked; a bad file raises ``ValueError`` naming the key by its dotted
path, e.g. ``controller.1.actuate``; every number, alone or in an array, is a TOML integer or
float: a string such as ``"8"`` or a boolean is refused, naming the entry, e.g.
``system.masses[1]``)::

    [system]
    dofs = ["load", "gear", "motor"]     # unique names, n = len(dofs)
    mass = [[...], ...]                  # M (n x n, symmetric positive definite)
    # masses = [m_1, ..., m_n]           # or a diagonal M (not both)
    damping = [[...]]                    # C (optional, zeros)
    stiffness = [[...]]                  # K (optional, zeros)
    input = [0.0, 0.0, 1.0]              # B (n,): where a controller without actuate acts

    [[contact]]                          # one of: between = [a, b] (gap q_a - q_b),
    between = ["load", "gear"]           #   dof = "name" (gap q_dof), normal = [w_1..w_n]
    lo = -0.75                           # either bound may be omitted (not both)
    hi = 0.75
    restitution = 0.5                    # rigid; or stiffness = k, damping = c (compliant)

    [controller]                         # one controller; or repeated [[controller]] tables
    type = "pd"                          # "pd" (kp, kv) | "pid" (kp, ki, kd, filter_time)
                                         #   | "tf" (num, den) | "ss" (A, B, C, D)
    kp = 10.0
    kv = 20.0
    measure = "gear"                     # DOF name (or a list of n weights)
    # actuate = "motor"                  # where its force acts (default: [system] input)
    # measure_velocity = "motor"         # velocity sensor elsewhere (default: as measure)
    # dt = 0.001                         # discrete-time controller, zero-order hold
    # delay = 0                          # input delay in whole samples (with dt)
    # [controller.reference]             # its own reference (default: [reference])

    [reference]                          # "sine" | "constant" | "sum_of_sines"; optional
    type = "sine"                        #   (default: constant 0)
    amplitude = 1.0
    omega = 5.0
    feedforward_mass = 1.0               # adds feedforward_mass * xd'' (default 0)

    [initial]
    q = [0.3, 0.0, 0.0]                  # default zeros
    v = [0.5, 0.0, 0.0]                  # default zeros
    t0 = 0.0                             # default 0

Semantics: ``u = feedforward_mass xd'' + kp (xd - q_m) + kv (xd' - v_m)`` along ``actuate``
(``pid``: ``u_fb = kp err + ki int(err) + kd d``, ``d`` the derivative ``err_dot`` through
a first-order filter ``d' = (err_dot - d) / filter_time``, unfiltered when ``filter_time``
is 0 or absent; ``ki``, ``kd`` default 0; with ``dt`` the same controller sampled with a
zero-order hold, i.e. its exact discretisation at the sampling instants)
(``tf``: from ``err = xd - y``; ``ss``: from ``err`` or ``[err, err_dot]``, by the number of
inputs; with ``dt`` both are taken as discrete-time as written); ``sine`` is
``xd = amplitude cos(omega t)`` in absolute time, ``constant`` is ``xd = value``,
``sum_of_sines`` is ``sum amplitudes[i] cos(omegas[i] t)``.

``[system] input`` next to the controllers: it is the direction of every controller that
gives no ``actuate``; it is required when some controller omits ``actuate`` and refused when
none does (it would act nowhere). A single ``[controller]`` table without ``actuate`` with
``input`` is the file format of one controller, unchanged.
"""
from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hybridpd._results import compact_repr
from hybridpd.loop import Controller
from hybridpd.mechanics.automaton import MechanicalAutomaton, build_automaton
from hybridpd.mechanics.contacts import Contact
from hybridpd.mechanics.loop import ControlChannel, Reference, mechanical_loop
from hybridpd.mechanics.system import MechanicalSystem

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["CONTROLLER_NAMES", "MechanicalModel", "describe_controller", "describe_controllers",
           "load_model", "model_from_dict"]

_TABLES = {
    "system": {"dofs", "mass", "masses", "damping", "stiffness", "input"},
    "contact": {"between", "dof", "normal", "lo", "hi", "restitution", "stiffness", "damping",
                "name"},
    "controller": {"type", "kp", "kv", "num", "den", "A", "B", "C", "D", "measure",
                   "measure_velocity", "actuate", "dt", "delay", "ki", "kd", "filter_time",
                   "reference"},
    "reference": {"type", "amplitude", "omega", "feedforward_mass", "value", "amplitudes",
                  "omegas"},
    "initial": {"q", "v", "t0"},
}
_CTRL_KEYS = {"pd": {"kp", "kv"}, "tf": {"num", "den"}, "ss": {"A", "B", "C", "D"},
              "pid": {"kp", "ki", "kd", "filter_time"}}
_CTRL_OPTIONAL = {"ss": {"A"}, "pid": {"ki", "kd", "filter_time"}}
_CTRL_COMMON = {"type", "measure", "measure_velocity", "actuate", "dt", "delay", "reference"}
_REF_KEYS = {"sine": {"amplitude", "omega", "feedforward_mass"}, "constant": {"value"},
             "sum_of_sines": {"amplitudes", "omegas", "feedforward_mass"}}


@dataclass(frozen=True, eq=False)  # array fields: identity semantics
class MechanicalModel:
    """A loaded model file.

    Attributes
    ----------
    system : MechanicalSystem
    contacts : tuple of Contact
    automaton : MechanicalAutomaton
        The closed loop with its contacts (``automaton.loop`` is the loop).
    x0 : ndarray, shape (2n,)
        Initial mechanical state ``[q_1, v_1, ..., q_n, v_n]``.
    t0 : float
        Initial time.
    source : str
        File name (or ``"<dict>"``).
    """

    system: MechanicalSystem
    contacts: tuple
    automaton: MechanicalAutomaton = field(repr=False)
    x0: np.ndarray
    t0: float
    source: str = "<dict>"
    __repr__ = compact_repr

    def simulate(self, t_end: float, max_impacts: int = 100_000, **options):
        """Simulate from the file's initial state over ``[t0, t_end]``."""
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.mechanics.simulate import simulate

        if not float(t_end) > self.t0:
            raise ValueError(f"t_end must be > t0 = {self.t0:g}, got {t_end!r}")
        return simulate(self.automaton, self.x0, (self.t0, float(t_end)),
                        max_impacts=max_impacts, **options)


def load_model(path) -> MechanicalModel:
    """Load a TOML model file (see the module docstring); ``ValueError`` naming the key.

    Examples
    --------
    >>> from pathlib import Path
    >>> import hybridpd
    >>> f = Path(hybridpd.__file__).parents[1] / "examples" / "models" / "impact_pair.toml"
    >>> m = load_model(f) if f.exists() else None
    >>> m is None or m.system.dofs == ("x1", "x2")
    True
    """
    data, p = read_model_file(path)
    return model_from_dict(data, source=str(p))


def read_model_file(path) -> tuple:
    """``(table, Path)``: the parsed TOML of a model file, unchecked.

    Raises ``ValueError`` naming the file when it cannot be read or is not valid TOML.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise ValueError(f"model file {str(path)!r}: cannot read ({exc.strerror})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"model file {p.name}: invalid TOML ({exc})") from None
    return data, p


def _check_keys(where, table, allowed):
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table")
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ValueError(f"{where}.{unknown[0]}: unknown key (allowed: {sorted(allowed)})")


def _numbers(key, value):
    """Refuse anything but numbers in `value` (a number, or nested lists of numbers): a TOML
    string (``kp = "8"``) or boolean (``kp = true``) is no number, although NumPy would read
    it as one. The message names the entry (``system.masses[1]``)."""
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _numbers(f"{key}[{i}]", v)
        return
    if isinstance(value, np.ndarray) and value.dtype.kind in "iuf":
        return
    if isinstance(value, (int, float, np.integer, np.floating)) \
            and not isinstance(value, (bool, np.bool_)):
        return
    if isinstance(value, str):
        what = f"the string {json.dumps(value)}"
    elif isinstance(value, (bool, np.bool_)):
        what = f"the boolean {str(bool(value)).lower()}"
    else:
        what = f"{value!r} ({type(value).__name__})"
    raise ValueError(f"{key}: must be a number (a TOML integer or float, without quotes), "
                     f"got {what}")


def _array(key, value, shape=None):
    _numbers(key, value)
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{key}: must be numbers, got {value!r}") from None
    if shape is not None and a.shape != shape:
        raise ValueError(f"{key}: must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{key}: must be finite")
    return a


def _reraise(key, fn, *args, **kw):
    try:
        return fn(*args, **kw)
    except ValueError as exc:
        raise ValueError(f"{key}: {exc}") from None


def model_from_dict(data: dict, source: str = "<dict>") -> MechanicalModel:
    """Build a :class:`MechanicalModel` from the parsed TOML tables (same checks as a file)."""
    if not isinstance(data, dict):
        raise ValueError("model must be a table")
    unknown = sorted(set(data) - set(_TABLES))
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown table (allowed: {sorted(_TABLES)})")
    for t in ("system", "controller"):
        if t not in data:
            raise ValueError(f"{t}: missing table [{t}]")
    system = _system(data["system"])
    raw = data.get("contact", [])
    if isinstance(raw, dict):
        raw = [raw]
    if not isinstance(raw, list):
        raise ValueError("contact: must be an array of tables [[contact]]")
    contacts = tuple(_contact(f"contact[{i}]", c, system) for i, c in enumerate(raw))
    reference = _reference(data.get("reference", {"type": "constant", "value": 0.0}),
                           "reference")
    tables = _controller_tables(data["controller"])
    system = _actuation(data["system"], system, tables)
    channels = [_controller(where, t, system) for where, t in tables]
    # the loop's reference is the file's; without a [reference] table it is the first
    # controller's own (so that a phase is read from what is tracked)
    own = all(ch.reference is not None for ch in channels)
    loop = _reraise("controller", mechanical_loop, system, channels,
                    None if own and "reference" not in data else reference)
    model = build_automaton(loop, contacts)
    x0, t0 = _initial(data.get("initial", {}), system)
    z0 = loop.initial_state(x0[0::2], x0[1::2], t0)
    model.initial_mode(z0)
    return MechanicalModel(system, contacts, model, x0, t0, source)


def _system(t) -> MechanicalSystem:
    _check_keys("system", t, _TABLES["system"])
    if "dofs" not in t:
        raise ValueError("system.dofs: required (list of DOF names)")
    dofs = t["dofs"]
    if not isinstance(dofs, list) or not all(isinstance(d, str) for d in dofs) or not dofs:
        raise ValueError("system.dofs: must be a non-empty list of names")
    dup = sorted({d for d in dofs if dofs.count(d) > 1})
    if dup:
        raise ValueError(f"system.dofs: duplicate DOF names {dup}")
    n = len(dofs)
    if "mass" in t and "masses" in t:
        raise ValueError("system.masses: give either mass (matrix) or masses (diagonal), "
                         "not both")
    if "mass" in t:
        M = _array("system.mass", t["mass"], (n, n))
    elif "masses" in t:
        m = _array("system.masses", t["masses"], (n,))
        if not np.all(m > 0):
            raise ValueError("system.masses: must all be > 0")
        M = np.diag(m)
    else:
        raise ValueError("system.mass: required (or masses)")
    C = _array("system.damping", t["damping"], (n, n)) if "damping" in t else None
    K = _array("system.stiffness", t["stiffness"], (n, n)) if "stiffness" in t else None
    B = _array("system.input", t["input"], (n,)) if "input" in t else None
    try:
        return MechanicalSystem(tuple(dofs), M, C, K, B)
    except ValueError as exc:
        msg = str(exc)
        key = msg.split(" ", 1)[0].rstrip(":")
        raise ValueError(f"system.{msg}" if key in ("mass", "damping", "stiffness", "input")
                         else f"system: {msg}") from None


def _contact(where, t, system) -> Contact:
    _check_keys(where, t, _TABLES["contact"])
    forms = [k for k in ("between", "dof", "normal") if k in t]
    if len(forms) != 1:
        raise ValueError(f"{where}.between: give exactly one of between / dof / normal, got "
                         f"{forms or 'none'}")
    form = forms[0]
    n = system.n
    if form == "between":
        pair = t["between"]
        if (not isinstance(pair, list) or len(pair) != 2
                or not all(isinstance(d, str) for d in pair) or pair[0] == pair[1]):
            raise ValueError(f"{where}.between: must be two different DOF names")
        w = np.zeros(n)
        w[_reraise(f"{where}.between", system.index, pair[0])] = 1.0
        w[_reraise(f"{where}.between", system.index, pair[1])] = -1.0
    elif form == "dof":
        if not isinstance(t["dof"], str):
            raise ValueError(f"{where}.dof: must be a DOF name")
        w = np.zeros(n)
        w[_reraise(f"{where}.dof", system.index, t["dof"])] = 1.0
    else:
        w = _array(f"{where}.normal", t["normal"], (n,))
    if "restitution" in t and ("stiffness" in t or "damping" in t):
        raise ValueError(f"{where}.restitution: give restitution (rigid) or stiffness/damping "
                         "(compliant), not both")
    for k in ("lo", "hi", "restitution", "stiffness", "damping"):
        if k in t:
            _array(f"{where}.{k}", t[k], ())
    if "lo" in t and "hi" in t and not float(t["lo"]) < float(t["hi"]):
        raise ValueError(f"{where}.lo: must be < hi, got lo = {t['lo']!r}, hi = {t['hi']!r}")
    if "lo" not in t and "hi" not in t:
        raise ValueError(f"{where}.hi: give lo, hi or both")
    if "restitution" in t and not 0.0 <= float(t["restitution"]) <= 1.0:
        raise ValueError(f"{where}.restitution: must be in [0, 1], got {t['restitution']!r}")
    if "damping" in t and "stiffness" not in t:
        raise ValueError(f"{where}.stiffness: required with damping (compliant contact)")
    if "stiffness" in t and not float(t["stiffness"]) > 0:
        raise ValueError(f"{where}.stiffness: must be > 0, got {t['stiffness']!r}")
    if "damping" in t and not float(t["damping"]) >= 0:
        raise ValueError(f"{where}.damping: must be >= 0, got {t['damping']!r}")
    name = t.get("name", "")
    if not isinstance(name, str):
        raise ValueError(f"{where}.name: must be a string")
    return _reraise(where, Contact, w, t.get("lo"), t.get("hi"), t.get("restitution"),
                    t.get("stiffness"), t.get("damping"), name)


def _reference(t, where) -> Reference:
    _check_keys(where, t, _TABLES["reference"])
    kind = t.get("type", "sine")
    if kind not in _REF_KEYS:
        raise ValueError(f"{where}.type: must be one of {sorted(_REF_KEYS)}, got {kind!r}")
    extra = sorted(set(t) - _REF_KEYS[kind] - {"type"})
    if extra:
        raise ValueError(f"{where}.{extra[0]}: not a key of type {kind!r}")
    ff = t.get("feedforward_mass", 0.0)
    if kind == "sine":
        for k in ("amplitude", "omega"):
            if k not in t:
                raise ValueError(f"{where}.{k}: required for type 'sine'")
        a = float(_array(f"{where}.amplitude", t["amplitude"], ()))
        w = float(_array(f"{where}.omega", t["omega"], ()))
        if a < 0:
            raise ValueError(f"{where}.amplitude: must be >= 0, got {a!r}")
        if not w > 0:
            raise ValueError(f"{where}.omega: must be > 0, got {w!r}")
        _array(f"{where}.feedforward_mass", ff, ())
        return _reraise(f"{where}.feedforward_mass", Reference.sine, a, w, ff)
    if kind == "constant":
        if "value" not in t:
            raise ValueError(f"{where}.value: required for type 'constant'")
        return Reference.constant(float(_array(f"{where}.value", t["value"], ())))
    for k in ("amplitudes", "omegas"):
        if k not in t:
            raise ValueError(f"{where}.{k}: required for type 'sum_of_sines'")
    _array(f"{where}.feedforward_mass", ff, ())
    a = _array(f"{where}.amplitudes", t["amplitudes"])
    w = _array(f"{where}.omegas", t["omegas"], a.shape)
    if a.ndim != 1:
        raise ValueError(f"{where}.amplitudes: must be a list of numbers")
    if np.any(a < 0) or np.any(w <= 0):
        raise ValueError(f"{where}.omegas: amplitudes must be >= 0 and omegas > 0")
    return _reraise(f"{where}.feedforward_mass", Reference.sum_of_sines, a, w, ff)


def _controller_tables(raw):
    """``[(where, table)]``: a single ``[controller]`` table is ``controller``, repeated
    ``[[controller]]`` tables are ``controller.0``, ``controller.1``, ..."""
    if isinstance(raw, dict):
        return [("controller", raw)]
    if isinstance(raw, list) and raw and all(isinstance(t, dict) for t in raw):
        return [(f"controller.{i}", t) for i, t in enumerate(raw)]
    raise ValueError("controller: must be a table [controller] or a non-empty array of tables "
                     "[[controller]]")


def _actuation(table, system, tables):
    """Check ``[system] input`` against the controllers' ``actuate`` (module docstring)."""
    omit = [where for where, t in tables if isinstance(t, dict) and "actuate" not in t]
    if "input" in table and not omit:
        raise ValueError("system.input: not used: every controller gives actuate (remove "
                         "input, or leave actuate out of the controllers that act along it)")
    if "input" not in table and omit:
        if len(tables) == 1 and "actuate" not in tables[0][1]:
            raise ValueError(f"system.input: required (B, {system.n} numbers), or give "
                             f"{omit[0]}.actuate")
        raise ValueError(f"{omit[0]}.actuate: required (a DOF name or {system.n} weights): "
                         "there is no [system] input to act along")
    return system


def _controller(where, t, system) -> ControlChannel:
    """One ``[controller]`` / ``[[controller]]`` table as a :class:`ControlChannel`."""
    _check_keys(where, t, _TABLES["controller"])
    kind = t.get("type")
    if kind not in _CTRL_KEYS:
        raise ValueError(f"{where}.type: must be one of {sorted(_CTRL_KEYS)}, got {kind!r}")
    extra = sorted(set(t) - _CTRL_KEYS[kind] - _CTRL_COMMON)
    if extra:
        raise ValueError(f"{where}.{extra[0]}: not a key of type {kind!r}")
    for k in sorted(_CTRL_KEYS[kind] - _CTRL_OPTIONAL.get(kind, set())):
        if k not in t:
            raise ValueError(f"{where}.{k}: required for type {kind!r}")
    if "measure" not in t:
        raise ValueError(f"{where}.measure: required (the measured DOF)")
    measure = _measured(t, "measure", system, where)
    measure_v = _measured(t, "measure_velocity", system, where) if "measure_velocity" in t \
        else None
    actuate = _measured(t, "actuate", system, where) if "actuate" in t else None
    reference = _reference(t["reference"], f"{where}.reference") if "reference" in t else None
    dt = 0.0
    if "dt" in t:
        dt = float(_array(f"{where}.dt", t["dt"], ()))
        if not dt > 0:
            raise ValueError(f"{where}.dt: must be > 0 (sampling period), got {t['dt']!r}")
    delay = t.get("delay", 0)
    if isinstance(delay, bool) or not isinstance(delay, int) or delay < 0:
        raise ValueError(f"{where}.delay: must be an integer >= 0, got {delay!r}")
    if delay and not dt:
        raise ValueError(f"{where}.delay: needs a discrete-time controller (give dt)")
    if kind == "pd":
        kp = float(_array(f"{where}.kp", t["kp"], ()))
        kv = float(_array(f"{where}.kv", t["kv"], ()))
        sysc = Controller(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)),
                          np.array([[kp, kv]]), dt)
    elif kind == "pid":
        sysc = _pid(t, dt, where)
    elif kind == "tf":
        sysc = _tf(t, dt, where)
    else:
        sysc = _ss(t, dt, where)
    return _reraise(where, ControlChannel, sysc, measure, actuate, reference, measure_v, delay)


def _tf(t, dt, where):
    num = _array(f"{where}.num", t["num"])
    den = _array(f"{where}.den", t["den"])
    if num.ndim != 1 or den.ndim != 1 or not den.size or den[0] == 0:
        raise ValueError(f"{where}.den: num and den must be coefficient lists with a "
                         "non-zero leading den coefficient")
    if np.trim_zeros(num, "f").size > den.size:
        raise ValueError(f"{where}.num: improper transfer function (degree of num > "
                         "degree of den) cannot be realised")
    import control as ct  # deferred import: python-control realises transfer functions

    return ct.tf(num, den, dt)


def _ss(t, dt, where):
    D = np.atleast_2d(_array(f"{where}.D", t["D"]))
    if D.shape not in ((1, 1), (1, 2)):
        raise ValueError(f"{where}.D: must have shape (1, 1) or (1, 2), got {D.shape}")
    m = D.shape[1]
    if "A" in t and np.size(t["A"]):
        A = np.atleast_2d(_array(f"{where}.A", t["A"]))
        k = A.shape[0]
        if A.shape != (k, k):
            raise ValueError(f"{where}.A: must be square, got {A.shape}")
        B = _array(f"{where}.B", t["B"]).reshape(k, -1) if np.size(t["B"]) == k * m \
            else _array(f"{where}.B", t["B"], (k, m))
        C = _array(f"{where}.C", t["C"]).reshape(1, -1)
        if C.shape != (1, k):
            raise ValueError(f"{where}.C: must have shape (1, {k}), got {C.shape}")
    else:
        A, B, C = np.zeros((0, 0)), np.zeros((0, m)), np.zeros((1, 0))
    return Controller(A, np.asarray(B, float), C, D, dt)


def _pid(t, dt, where="controller"):
    """The PID of a model file as a state-space controller from ``[err, err_dot]``; with
    ``dt`` its exact zero-order-hold discretisation (:meth:`Controller.sample`)."""
    g = {k: float(_array(f"{where}.{k}", t.get(k, 0.0), ())) for k in
         ("kp", "ki", "kd", "filter_time")}
    if g["filter_time"] < 0:
        raise ValueError(f"{where}.filter_time: must be >= 0 (time units), got "
                         f"{g['filter_time']!r}")
    # states: the integral of err, then (with a filter) the filtered derivative
    A, B, C = [], [], []
    D = [g["kp"], 0.0]
    if g["ki"]:
        A.append([0.0])
        B.append([1.0, 0.0])
        C.append(g["ki"])
    if g["kd"] and g["filter_time"] > 0:
        A.append([-1.0 / g["filter_time"]])
        B.append([0.0, 1.0 / g["filter_time"]])
        C.append(g["kd"])
    else:
        D[1] = g["kd"]
    k = len(A)
    Am = np.diag([a[0] for a in A]) if k else np.zeros((0, 0))
    sysc = Controller(Am, np.array(B).reshape(k, 2), np.array(C).reshape(1, k), np.array([D]))
    return sysc.sample(dt) if dt else sysc


def _measured(t, key, system, where="controller"):
    m = t[key]
    if isinstance(m, str):
        _reraise(f"{where}.{key}", system.index, m)
        return m
    w = _array(f"{where}.{key}", m, (system.n,))
    if not np.any(w):
        raise ValueError(f"{where}.{key}: all {system.n} weights are zero (give a DOF name or "
                         "weights that are not all zero)")
    return w


def _initial(t, system):
    _check_keys("initial", t, _TABLES["initial"])
    n = system.n
    q = _array("initial.q", t.get("q", [0.0] * n), (n,))
    v = _array("initial.v", t.get("v", [0.0] * n), (n,))
    t0 = float(_array("initial.t0", t.get("t0", 0.0), ()))
    x0 = np.empty(2 * n)
    x0[0::2], x0[1::2] = q, v
    return x0, t0


#: How a controller type reads in words (figure titles, summaries).
CONTROLLER_NAMES = {"pd": "PD", "pid": "PID", "p": "P", "pi": "PI",
                    "tf": "transfer-function controller", "ss": "state-space controller"}


def describe_controller(table: dict) -> str:
    """A model file's controller table in words: its type, whether it is sampled (and its
    period ``dt``, in the file's time unit) and the DOF it measures.

    Examples
    --------
    >>> describe_controller({"type": "pid", "kp": 20, "dt": 0.001, "measure": "motor"})
    'sampled PID on motor (dt = 0.001)'
    >>> describe_controller({"type": "pd", "kp": 20, "kv": 5})
    'continuous PD'
    """
    kind = str(table.get("type", "")).strip().lower()
    name = CONTROLLER_NAMES.get(kind, f"{kind} controller" if kind else "controller")
    dt = table.get("dt")
    sampled = isinstance(dt, (int, float)) and not isinstance(dt, bool) and dt > 0
    text = f"{'sampled' if sampled else 'continuous'} {name}"
    if table.get("measure") is not None:
        measure = table["measure"]
        text += f" on {measure if isinstance(measure, str) else ', '.join(map(str, measure))}"
    return text + (f" (dt = {dt:g})" if sampled else "")


def describe_controllers(data: dict) -> str:
    """Every controller of a parsed model file (``[controller]`` or ``[[controller]]``) in
    words (:func:`describe_controller`), joined by ``" + "``.

    Examples
    --------
    >>> describe_controllers({"controller": [{"type": "pd"}, {"type": "pid", "dt": 0.01}]})
    'continuous PD + sampled PID (dt = 0.01)'
    """
    tables = data.get("controller") if isinstance(data, dict) else None
    if isinstance(tables, dict):
        tables = [tables]
    if not tables:
        return "no controller"
    return " + ".join(describe_controller(t) for t in tables if isinstance(t, dict))
