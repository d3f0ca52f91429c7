"""The public API: a flat, lazily loaded namespace, and no compatibility layer.

``import hybridpd as hp`` gives every workflow name; importing the package loads none of the
heavy libraries, and the general path loads no module of the impact pair. Module paths of
earlier versions, and names moved since, are gone (the CHANGELOG lists them): importing one
fails, naming it, instead of being served with a warning.
"""
import importlib
import inspect
import json
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

import hybridpd as hp

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("numba", "sympy", "control", "matplotlib", "xarray", "scipy", "dask", "zarr")

# Every module path of the first version, the module that replaced it, and its public names
# then (read from the repository's history).
OLD_MODULES = {
    "hybridpd.analysis.sections": ("hybridpd.mechanics.sections", "mechanical_section mode_code"),
    "hybridpd.analysis.hybridcont": ("hybridpd.analysis.continuation", """
        BifurcationEvent Branch BranchPoint EVENT_KINDS continue_orbit
    """),
    "hybridpd.automaton": ("hybridpd.hybrid.automaton", """
        Guard HybridAutomaton HybridTrajectory Jump JumpTable Mode PackedAutomaton
        Segment SegmentTable TerminationCause ZenoOptions run_hybrid
    """),
    "hybridpd.basins": ("hybridpd.pair.basins", """
        BasinResult ImpactMapper LABELS basin_of_attraction load_basin section_grid
    """),
    "hybridpd.batch": ("hybridpd.pair.batch", """
        LABELS STATUS_IMPACT STATUS_NONFINITE STATUS_STICK STATUS_TIMEOUT
        STATUS_UNRESOLVED impact_map iterate_map map_labels next_impact pack_params
    """),
    "hybridpd.continuation": ("hybridpd.pair.continuation", """
        BifurcationEvent Branch EVENT_KINDS ImpactStep MapTrace PARAMETERS
        SYMMETRIC_PARAMETERS continue_orbit continue_symmetric
        map_power_jacobian trace_map
    """),
    "hybridpd.design": ("hybridpd.pair.design", """
        ComparisonRow DesignMap DesignResult InfeasibleDesignError OptimizerRun
        PLANT_STATUS RobustReport RobustnessComparison design design_objective
        robustness robustness_comparison shifted_amplitude shifted_orbit
    """),
    "hybridpd.events": ("hybridpd.hybrid.events", """
        CrossingResult EV_CROSSING EV_GRAZING EV_NONE EV_NONFINITE EV_START
        EV_STEP_LIMIT K_DEFAULT LTIModeData THETA_DEFAULT advance first_crossing
        flow_eval flow_to lti_flow prepare_lti_mode
    """),
    "hybridpd.impactmap": ("hybridpd.pair.impactmap", """
        ImpactMap MapResult Stability stability
    """),
    "hybridpd.impactpair": ("hybridpd.pair.impactpair", """
        ControlledImpactPair ImpactPairTrajectory
    """),
    "hybridpd.lti": ("hybridpd.pair.lti", """
        LTIJacobian LTIOrbitResult LTI_REASONS filtered_pd
        filtered_pid lead_lag lti_symmetric_orbit
    """),
    "hybridpd.naive": ("hybridpd.pair.naive", """
        NaiveResult naive_simulate
    """),
    "hybridpd.orbits": ("hybridpd.pair.orbits", """
        OrbitArrays REASONS SymmetricOrbitResult symmetric_orbit symmetric_orbits
    """),
    "hybridpd.regions": ("hybridpd.pair.regions", """
        AXES SymmetricFamily
    """),
    "hybridpd.samples": ("hybridpd.hybrid.samples", """
        ball_initial_state bouncing_ball impact_oscillator oscillator_initial_state
    """),
    "hybridpd.sweep": ("hybridpd.sweeps.sweep", """
        ChunkError EXECUTORS ExecutorSpec FORMAT SweepResult default_chunk_size
        grid_points load_sweep resolve_executor run_sweep
    """),
    "hybridpd.symbolic": ("hybridpd.pair.symbolic", """
        Derivation ImpactMapResult JacobianResult SymmetricOrbit dch derivation dsh
        flight_block flight_section_map flight_time flow gap gap_derivatives
        impact_block closed_form_map impact_section_map map_jacobian orbit_jacobian
        section_from_state state_from_section solve_symmetric_orbit symmetric_velocities
        sympy_functions system_matrix transition_matrix virtual_restitution
    """),
}

# Names moved out of a module that still exists: (old module, name, new module).
MOVED_NAMES = [
    ("hybridpd.pair.basins", "BasinMeasure", "hybridpd.analysis.basins"),
    ("hybridpd.pair.basins", "format_percent", "hybridpd._format"),
    ("hybridpd.pair.basins", "BasinResult", "hybridpd.analysis.basins"),
    ("hybridpd.pair.basins", "load_basin", "hybridpd.analysis.basins"),
    ("hybridpd.pair.basins", "LABELS", "hybridpd.analysis.labels"),
    ("hybridpd.pair.basins", "BasinMeasure", "hybridpd.analysis.basins"),
    ("hybridpd.analysis.periodic", "section_basin", "hybridpd.sweeps.basins"),
    ("hybridpd.analysis.periodic", "SectionMapper", "hybridpd.analysis.mappers"),
    ("hybridpd.analysis.certify", "BasinMapper", "hybridpd.analysis.mappers"),
    ("hybridpd.pair.basins", "ImpactMapper", "hybridpd.analysis.mappers"),
    ("hybridpd.pair.basins", "attractor_basin", "hybridpd.sweeps.basins"),
    ("hybridpd.analysis.basins", "basin_of_attraction", "hybridpd.sweeps.basins"),
    ("hybridpd.analysis.basins", "Catalogue", "hybridpd.analysis.mappers"),
    ("hybridpd.analysis.periodic", "orbit_from_model", "hybridpd.analysis.model_orbits"),
    ("hybridpd.analysis.hybridmap", "impact_pair_section", "hybridpd.pair.section"),
    ("hybridpd.analysis.hybridmap", "mechanical_section", "hybridpd.mechanics.sections"),
    ("hybridpd.pair.continuation", "PeriodicOrbit", "hybridpd.analysis.periodic"),
    ("hybridpd.analysis.continuation", "continue_symmetric", "hybridpd.pair.continuation"),
    ("hybridpd.analysis.continuation", "switch_branch", "hybridpd.pair.continuation"),
    ("hybridpd.pair.continuation", "plot_branch", "hybridpd.plotting.branches"),
    ("hybridpd.pair.regions", "RegionMap", "hybridpd.sweeps.regions"),
    ("hybridpd.pair.regions", "load_region_map", "hybridpd.sweeps.regions"),
    ("hybridpd.pair.bifdiagram", "BifurcationDiagram", "hybridpd.analysis.diagrams"),
    ("hybridpd.pair.bifdiagram", "load_diagram", "hybridpd.analysis.diagrams"),
    ("hybridpd.pair.bifdiagram", "CLASSES", "hybridpd.analysis.diagrams"),
]


def _probe(code: str) -> dict:
    """Run ``code`` in a fresh interpreter; it prints one JSON object."""
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                       timeout=300, check=False)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


def test_import_loads_no_heavy_library():
    out = _probe("import sys, json, hybridpd; "
                 "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in "
                 f"{HEAVY!r})))")
    assert out == [], f"import hybridpd loaded {out}"


@pytest.mark.parametrize("name", ["find_orbit", "SectionMap", "continue_orbit", "load_model",
                                  "simulate", "HybridAutomaton", "stability", "basin_of_attraction",
                                  "mapper"])
def test_general_names_load_no_pair_module(name):
    out = _probe(f"import sys, json, hybridpd as hp; hp.{name}; "
                 "print(json.dumps(sorted(m for m in sys.modules "
                 "if m.startswith('hybridpd.pair'))))")
    assert out == [], f"hp.{name} loaded {out}"


def test_every_public_name_resolves():
    assert len(hp.__all__) >= 30
    assert hp.__all__ == sorted(hp.__all__)
    assert set(hp.__all__) == set(hp._NAMES) | {"__version__", "reproduce"}
    for name in hp.__all__:
        assert getattr(hp, name) is not None, name
    assert set(hp.__all__) <= set(dir(hp))


def test_flat_names_are_the_defining_objects():
    from hybridpd.analysis.periodic import find_orbit
    from hybridpd.mechanics.modelfile import load_model
    from hybridpd.model import ImpactPair

    assert hp.find_orbit is find_orbit and hp.load_model is load_model
    assert hp.ImpactPair is ImpactPair


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        hp.nonexistent  # noqa: B018
    # the basin names of earlier versions: one mapper and one basin_of_attraction now
    for old in ("ImpactMapper", "SectionMapper", "attractor_basin", "section_basin"):
        with pytest.raises(AttributeError, match=f"no attribute '{old}'"):
            getattr(hp, old)


def test_reproduce_is_callable_as_name_and_as_package():
    import hybridpd.reproduce as pkg

    assert callable(hp.reproduce) and callable(pkg)
    assert pkg.Settings is not None
    with pytest.raises(ValueError, match="mode"):
        hp.reproduce(mode="fastest")


# Names replaced by another (old module, old name, new module, new name).
RENAMED = [
    ("hybridpd.pair.basins", "AttractorBasin", "hybridpd.analysis.basins", "BasinResult"),
    ("hybridpd.pair.basins", "AttractorBasin", "hybridpd.analysis.basins",
     "BasinResult"),
    ("hybridpd.pair.basins", "load_attractor_basin", "hybridpd.analysis.basins",
     "load_basin"),
    ("hybridpd", "load_attractor_basin", "hybridpd.analysis.basins", "load_basin"),
    ("hybridpd.pair.continuation", "continue_pair_orbit", "hybridpd.analysis.continuation",
     "continue_orbit"),
    ("hybridpd.pair.continuation", "map_power_jacobian", "hybridpd.pair.impactmap",
     "ImpactMap"),
]


def test_old_module_paths_are_gone():
    for old in sorted(OLD_MODULES) + ["hybridpd.design", "hybridpd.sweeps.basin_result",
                                      "hybridpd.analysis.continuation.switching",
                                      "hybridpd.pair.attractors", "hybridpd.sweeps.section_basins",
                                      "hybridpd.sweeps.model_basins",
                                      "hybridpd.pair.continuation.branch",
                                      "hybridpd.pair.continuation.newton",
                                      "hybridpd.pair.continuation._common",
                                      "hybridpd.pair.continuation.events"]:
        sys.modules.pop(old, None)
        with pytest.raises(ModuleNotFoundError):
            importlib.import_module(old)
    assert not any(type(f).__name__ == "MovedModuleFinder" for f in sys.meta_path)
    root = [p.name for p in (ROOT / "hybridpd").glob("*.py")]
    assert len(root) <= 10, root


@pytest.mark.parametrize(("old", "name", "new"), MOVED_NAMES + [
    (o, n, m) for o, n, m, _ in RENAMED])
def test_moved_and_renamed_names_are_gone_from_their_old_modules(old, name, new):
    mod = importlib.import_module(old)
    with warnings.catch_warnings():
        warnings.simplefilter("error")       # no shim answers with a warning
        with pytest.raises(AttributeError, match="no attribute"):
            getattr(mod, name)
    importlib.import_module(new)             # the new home exists


def test_only_the_root_namespace_has_a_module_getattr():
    import ast

    found = []
    for f in sorted((ROOT / "hybridpd").rglob("*.py")):
        tree = ast.parse(f.read_text())
        for node in tree.body:
            names = ([node.name] if isinstance(node, ast.FunctionDef) else
                     [tg.id for tg in getattr(node, "targets", []) if isinstance(tg, ast.Name)])
            if "__getattr__" in names or "__path__" in names:
                found.append(str(f.relative_to(ROOT)))
    assert found == ["hybridpd/__init__.py"], found


def test_flat_names_have_docstrings_with_examples():
    missing = []
    for name in hp.__all__:
        if name == "__version__":
            continue
        if name in hp._SUBPACKAGES:  # reproduce: the callable package
            doc = inspect.getdoc(importlib.import_module(f"hybridpd.{name}")) or ""
        else:
            module = hp._NAMES[name]
            doc = inspect.getdoc(getattr(importlib.import_module(module), name)) or ""
        if "Examples\n--------" not in doc:
            missing.append(name)
    assert not missing, f"no Examples section: {missing}"


def test_continue_orbit_takes_a_builder_of_any_map():
    from hybridpd.hybrid.samples import impact_oscillator, oscillator_initial_state

    def build(w):
        return impact_oscillator(omega0=1.0, zeta=0.1, omega=w, stop=1.0, e=0.8)

    sec = {"mode": "free", "guard": "impact",
           "reference": (oscillator_initial_state(0, 0, omega=0.8), 0.0)}
    a = hp.continue_orbit(build, 0.8, 0.81, [7.7, 1.66], section=sec, step=0.01)
    assert a.termination == "reached" and a.parameter[-1] == pytest.approx(0.81)
    with pytest.raises(AttributeError):
        hp.continue_family  # noqa: B018
    with pytest.raises(ValueError, match="builder"):
        hp.continue_orbit("not a builder", 0.8, 0.81, [7.7, 1.66])


def test_no_public_name_is_defined_in_two_modules():
    import ast

    where = {}
    for path in sorted((ROOT / "hybridpd").rglob("*.py")):
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and not node.name.startswith("_"):
                where.setdefault(node.name, []).append(str(path.relative_to(ROOT)))
    twice = {k: v for k, v in where.items() if len(v) > 1 and k not in ("register", "run")}
    assert not twice, twice
