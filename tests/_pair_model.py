"""The impact pair as a model file (``xm = 0.4``, collocated PD 10/20, ``e = 0.5``), shared by
the tests of model-file analyses: as the parsed mapping and as the TOML text a user writes."""

PAIR = {
    "system": {"dofs": ["x1", "x2"], "masses": [0.1, 1.0], "input": [0.0, 1.0]},
    "contact": [{"between": ["x1", "x2"], "lo": -0.75, "hi": 0.75, "restitution": 0.5}],
    "controller": {"type": "pd", "kp": 10.0, "kv": 20.0, "measure": "x2"},
    "reference": {"type": "sine", "amplitude": 0.4, "omega": 5.0, "feedforward_mass": 1.0},
    "initial": {"q": [0.3, 0.0], "v": [0.5, 0.0]}}

PAIR_TOML = """
[system]
dofs = ["x1", "x2"]
masses = [0.1, 1.0]
input = [0.0, 1.0]
[[contact]]
between = ["x1", "x2"]
lo = -0.75
hi = 0.75
restitution = 0.5
[controller]
type = "pd"
kp = 10.0
kv = 20.0
measure = "x2"
[reference]
type = "sine"
amplitude = 0.4
omega = 5.0
feedforward_mass = 1.0
[initial]
q = [0.3, 0.0]
v = [0.5, 0.0]
"""
