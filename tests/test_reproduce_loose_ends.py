"""Loose ends met while reproducing the paper: CLI messages, bifurcation plots with their
branches, events whose location failed."""
import numpy as np
import pytest
from matplotlib.figure import Figure

from hybridpd.analysis.bifevents import EventTracker
from hybridpd.cli import main


@pytest.mark.parametrize("typo, guess", [("regoins", "regions"), ("plto", "plot"),
                                         ("reproduec", "reproduce")])
def test_a_misspelt_command_gets_a_did_you_mean(typo, guess, capsys):
    assert main([typo]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"did you mean {guess}?" in err[0], err


def test_a_negative_t_end_names_the_option(capsys):
    argv = ["simulate", "--case", "collocated", "--mu", "0.1", "--e", "0.5", "--L", "0.75",
            "--omega", "5", "--kp", "10", "--kv", "20", "--xm", "1", "--x0", "0.3", "0.5", "0",
            "0", "--t-end", "-1"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--t-end" in err[0] and "-1" in err[0], err


@pytest.mark.stored_data
def test_bifurcation_plot_draws_the_continued_branch_and_explains_the_period(
        tmp_path, monkeypatch, capsys):
    seen = []
    orig = Figure.savefig
    monkeypatch.setattr(Figure, "savefig",
                        lambda self, *a, **kw: (seen.append(self), orig(self, *a, **kw))[1])
    # collocated, e = 0.1: the symmetric orbit grazes at kv = 21.94 and the motion jumps to
    # a period-2 double-impact orbit
    argv = ["bifurcation", "--case", "collocated", "--mu", "0.1", "--e", "0.1", "--gamma",
            "0.75", "--omega", "5", "--kp", "10", "--param", "kv", "18", "26", "9",
            "--iterations", "200", "--keep", "20", "--follow", "--out",
            str(tmp_path / "d.nc"), "--plot", str(tmp_path / "d.png")]
    assert main(argv) == 0
    out = capsys.readouterr().out
    periods = next(ln for ln in out.splitlines() if "periods:" in ln)
    assert "1: " in periods and "2: " in periods, periods
    assert "repeat every k applications of P" in out
    assert "continued symmetric branch drawn" in out
    (fig,) = seen
    ax = fig.axes[0]
    labels = {ln.get_label() for ln in ax.lines}
    assert "period-1 branch (symmetric), stable" in labels and "grazing" in labels
    branch = next(ln for ln in ax.lines if ln.get_label().startswith("period-1 branch"))
    # the branch is the iterates' value where the diagram has period 1 (z1 = x2 at impact)
    x = np.asarray(branch.get_xdata(), float)
    y = np.asarray(branch.get_ydata(), float)
    assert np.nanmax(x[np.isfinite(y)]) == pytest.approx(21.938, abs=2e-3)
    assert "repeat every k applications" in " ".join(t.get_text() for t in ax.texts)


def test_an_event_whose_location_failed_is_uncertain():
    tracker = EventTracker(kinds=("fold",), evaluate=lambda pa, pb, th: None,
                       size=lambda pa, pb: 1.0, tol=1e-10, max_iter=50, locate=True,
                       to_event=lambda *a: a)
    _, pt, _, detail, _, ok = tracker.root(
        "fold", lambda p: p, -1.0, 2.0, 7, lambda pt: "fold: the branch turns back")
    assert not ok and detail.startswith("uncertain") and "corrector failed" in detail
    assert "between branch points 7 and 8" in detail
    # a converged location is reported as it is
    tracker = EventTracker(kinds=("fold",), evaluate=lambda pa, pb, th: pa + th * (pb - pa),
                       size=lambda pa, pb: 1.0, tol=1e-10, max_iter=200, locate=True,
                       to_event=lambda *a: a)
    _, pt, _, detail, _, ok = tracker.root(
        "fold", lambda p: p, -1.0, 2.0, 7, lambda pt: "fold: the branch turns back")
    assert ok and detail == "fold: the branch turns back" and abs(pt) < 1e-9
