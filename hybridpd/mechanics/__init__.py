"""Linear mechanical systems with clearances, stops and gear backlash under feedback.

``MechanicalSystem`` (``M q'' + C q' + K q = B u``) and its ``Contact`` list (rigid Newton or
compliant Kelvin-Voigt) are closed by any python-control controller
(:func:`mechanical_loop`, continuous or sampled-data, one controller or several, each a
:class:`ControlChannel`) and compiled into the project's hybrid
automaton (:func:`build_automaton`); :func:`simulate` runs it.
"""
from hybridpd.mechanics.automaton import MechanicalAutomaton, build_automaton
from hybridpd.mechanics.contacts import Contact
from hybridpd.mechanics.loop import (
    ControlChannel,
    LoopChannel,
    MechanicalLoop,
    Reference,
    mechanical_loop,
)
from hybridpd.mechanics.modelfile import MechanicalModel, load_model, model_from_dict
from hybridpd.mechanics.simulate import MechanicalTrajectory, simulate, simulate_state
from hybridpd.mechanics.system import MechanicalSystem
from hybridpd.mechanics.tables import GuardInfo, ModeInfo

__all__ = [
    "Contact",
    "ControlChannel",
    "GuardInfo",
    "LoopChannel",
    "MechanicalAutomaton",
    "MechanicalLoop",
    "MechanicalModel",
    "MechanicalSystem",
    "MechanicalTrajectory",
    "ModeInfo",
    "Reference",
    "build_automaton",
    "load_model",
    "mechanical_loop",
    "model_from_dict",
    "simulate",
    "simulate_state",
]
