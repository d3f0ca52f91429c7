"""Figures of users' model files: titles name the model's controllers (never a hard-coded
PD), and a simulated trajectory shows every degree of freedom at print size."""
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from matplotlib.text import Text

from hybridpd.cli import main
from hybridpd.mechanics.modelfile import describe_controllers
from hybridpd.plotting._common import model_title
from hybridpd.plotting.files import plot_file
from hybridpd.plotting.style import DOUBLE, MAX_HEIGHT, MIN_FONT

try:
    import tomllib
except ModuleNotFoundError:     # Python 3.10
    import tomli as tomllib

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"

#: the example drivetrain's plant under a continuous PID on the motor
PID_TOML = """
[system]
dofs = ["motor", "gear", "load"]
masses = [2.0, 0.2, 1.0]
damping = [[0.5, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.3]]
stiffness = [[40.0, -40.0, 0.0], [-40.0, 40.0, 0.0], [0.0, 0.0, 0.0]]
input = [1.0, 0.0, 0.0]
[[contact]]
name = "backlash"
between = ["load", "gear"]
lo = -0.1
hi = 0.1
restitution = 0.5
[controller]
type = "pid"
kp = 20.0
ki = 2.0
kd = 5.0
filter_time = 0.0
measure = "motor"
[reference]
type = "sine"
amplitude = 1.0
omega = 2.0
"""


def _texts(fig):
    return [t for t in fig.findobj(Text) if t.get_text().strip()]


def _all_text(fig) -> str:
    return "\n".join(t.get_text() for t in _texts(fig))


def test_controllers_described_from_the_model_file():
    
    with open(MODELS / "robot_joint.toml", "rb") as fh:
        data = tomllib.load(fh)
    assert describe_controllers(data) == "sampled PID on motor (dt = 0.001)"
    data["controller"] = [data["controller"], {"type": "pd", "measure": "load"}]
    assert describe_controllers(data) == ("sampled PID on motor (dt = 0.001) + continuous PD "
                                          "on load")
    assert model_title(MODELS / "drivetrain.toml") == "drivetrain.toml, continuous PD on motor"
    assert model_title("/nonexistent/x.toml") == "x.toml, the model's controller"
    assert model_title("/nonexistent/x.toml", {"controllers": "sampled PI"}) == \
        "x.toml, sampled PI"


@pytest.fixture(scope="module")
def pid_results(tmp_path_factory):
    """A region map, a basin and a diagram of a PID model file, written by the command line;
    the model file is then moved away, so the figures can only read what the files hold."""
    d = tmp_path_factory.mktemp("pid")
    model = d / "pid.toml"
    model.write_text(PID_TOML)
    m = str(model)
    out = {k: d / f"{k}.nc" for k in ("regions", "basin", "diagram")}
    assert main(["regions", "--model", m, "--x", "controller.kp", "15", "25", "2", "--y",
                 "controller.kd", "4", "6", "2", "--event", "release", "--out",
                 str(out["regions"]), "--quiet"]) == 0
    assert main(["basin", "--model", m, "--event", "release", "--x", "load", "-0.8", "0.8",
                 "3", "--y", "load_dot", "-6", "6", "3", "--iterations", "20", "--out",
                 str(out["basin"]), "--quiet"]) == 0
    assert main(["bifurcation", "--model", m, "--event", "release", "--param",
                 "controller.kp", "15", "25", "2", "--iterations", "20", "--keep", "10",
                 "--out", str(out["diagram"])]) == 0
    shutil.move(model, d / "elsewhere.toml")
    return out


@pytest.mark.parametrize("kind", ["regions", "basin", "diagram"])
def test_model_figures_name_the_pid_not_pd(pid_results, kind):
    fig = plot_file(pid_results[kind])
    text = _all_text(fig)
    assert "continuous PID on motor" in text and "pid.toml" in text
    assert not re.search(r"\bPD\b", text), text


def test_region_title_reads_the_model_file_when_the_result_does_not_say(tmp_path):
    from hybridpd.plotting.regions import plot_region_panels, plot_regions
    from hybridpd.sweeps.regions import RegionMap

    model = tmp_path / "joint.toml"
    shutil.copy(MODELS / "robot_joint.toml", model)
    z = np.zeros((1, 2, 2))
    rm = RegionMap("joint.toml", "controller.kp", "controller.kd", np.array([1.0, 2.0]),
                   np.array([1.0, 2.0]), np.array([0.3]),
                   {"model": str(model), "section_contact": 0, "section_event": "release"},
                   z.astype(bool), z.astype(bool), z, z.astype(np.int64))
    for fig in (plot_region_panels(rm), plot_regions(rm, ax=_axes())):
        text = _all_text(fig)
        assert "sampled PID on motor (dt = 0.001)" in text
        assert not re.search(r"\bPD\b", text)


def _axes():
    from matplotlib.figure import Figure

    return Figure(figsize=(DOUBLE, 3)).add_subplot(1, 1, 1)


def _chain(n):
    t = np.linspace(0.0, 6.0, 600)
    q = np.array([np.sin(t + 0.3 * i) * (1 + 0.05 * i) for i in range(n)]).T
    v = np.gradient(q, t, axis=0)
    contacts = [{"name": f"gap{i}", "normal": np.eye(n)[i] - np.eye(n)[i + 1], "lo": -0.2,
                 "hi": 0.2} for i in range(n - 1)]
    return t, q, v, contacts


@pytest.mark.parametrize("n", [3, 10])
def test_a_trajectory_figure_shows_every_dof_at_print_size(n, tmp_path):
    from hybridpd.cli._common import write_figure
    from hybridpd.plotting.trajectory import plot_trajectory_samples

    t, q, v, contacts = _chain(n)
    dofs = [f"m{i}" for i in range(n)]
    fig = plot_trajectory_samples(t, q, v, dofs=dofs, contacts=contacts,
                                  impact_times=[1.0, 2.0], impact_contacts=[0, n - 2],
                                  sticking=[(3.0, 3.5, 0), (3.2, 3.8, 1)], title="chain")
    phase = [ax for ax in fig.axes if ax.get_title().startswith("phase portrait")]
    assert sorted(ax.get_title().split(": ")[1] for ax in phase) == sorted(dofs)
    # every DOF has a position line of its own, drawn from its own column of q
    for i, name in enumerate(dofs):
        lines = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_label() == name]
        assert len(lines) == 1
        np.testing.assert_allclose(lines[0].get_ydata(), q[:, i], rtol=0, atol=0)
    gaps = [ln for ax in fig.axes for ln in ax.get_lines()
            if ln.get_label().startswith("gap")]
    assert len(gaps) == n - 1
    for ax in fig.axes:                 # at most six series per panel: no style repeats
        styles = [(ln.get_color(), ln.get_linestyle()) for ln in ax.get_lines()
                  if not ln.get_label().startswith("_") and ln.get_label() != "impacts"]
        assert len(styles) == len(set(styles))
    w, h = fig.get_size_inches()
    assert w == pytest.approx(DOUBLE, abs=1e-9) and h <= MAX_HEIGHT + 1e-9
    path = tmp_path / f"chain{n}.png"
    write_figure(fig, path)
    assert min(t.get_fontsize() for t in _texts(fig)) >= MIN_FONT
    import matplotlib.image

    img = matplotlib.image.imread(path)
    np.testing.assert_allclose(img.shape[1] / 300, DOUBLE, rtol=0, atol=0.02)
