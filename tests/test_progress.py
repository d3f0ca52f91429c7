"""The progress reporter: plain lines off a terminal (fake clock), a tqdm bar on one, silence."""
import io

import pytest

from hybridpd.sweeps.progress import Progress


class FakeClock:
    def __init__(self):
        self.t = 1000.0

    def __call__(self):
        return self.t


class FakeTTY(io.StringIO):
    def isatty(self):
        return True


def test_plain_lines_every_interval_and_a_final_line():
    out, clock = io.StringIO(), FakeClock()
    with Progress(40_000, "basin noncollocated e=0.1", file=out, clock=clock) as p:
        for _ in range(8):  # 5000 points every 4 s
            clock.t += 4.0
            p.update(5000)
    lines = out.getvalue().splitlines()
    # lines at 12 s, 24 s (>= 10 s since the previous line), then the final one at 32 s
    assert lines == [
        "basin noncollocated e=0.1: 15000/40000 points (38%), 12 s elapsed, ~20 s left",
        "basin noncollocated e=0.1: 30000/40000 points (75%), 24 s elapsed, ~8 s left",
        "basin noncollocated e=0.1: 40000/40000 points done in 32 s",
    ]


def test_short_loops_stay_silent_and_resumed_work_is_not_counted_as_speed():
    out, clock = io.StringIO(), FakeClock()
    with Progress(100, "quick", file=out, clock=clock) as p:
        clock.t += 1.5
        p.update(100)
    assert out.getvalue() == ""  # under `delay`: nothing at all
    out, clock = io.StringIO(), FakeClock()
    with Progress(1000, "resumed", file=out, clock=clock, initial=900, unit="step") as p:
        clock.t += 10.0
        p.update(50)  # 50 steps in 10 s -> 50 left take ~10 s (the 900 resumed are excluded)
    assert out.getvalue().splitlines()[0] == (
        "resumed: 950/1000 steps (95%), 10 s elapsed, ~10 s left")


def test_interrupted_loop_says_where_it_stopped():
    out, clock = io.StringIO(), FakeClock()
    with pytest.raises(KeyboardInterrupt), Progress(10, "reproduce fig6", file=out,
                                                    clock=clock, unit="step") as p:
        clock.t += 130.0
        p.update(3)
        raise KeyboardInterrupt
    assert out.getvalue().splitlines()[-1] == "reproduce fig6: stopped at 3/10 steps after 2.2 min"


def test_terminal_gets_a_labelled_tqdm_bar_counting_points():
    out = FakeTTY()
    with Progress(500, "regions collocated e=0.5", file=out, delay=0) as p:
        p.update(200)
        p.update(300)
    text = out.getvalue()
    assert "regions collocated e=0.5" in text and "500/500" in text and "point" in text


def test_disabled_is_silent():
    for stream in (io.StringIO(), FakeTTY()):
        with Progress(10, "x", file=stream, enabled=False, interval=0, delay=0) as p:
            p.update(10)
        assert stream.getvalue() == ""


@pytest.mark.parametrize("kw, match", [
    (dict(total=-1), "total"), (dict(total=2.5), "total"), (dict(label=None), "label"),
    (dict(enabled="no"), "enabled"), (dict(initial=20), "initial"),
    (dict(interval=-1), "interval"), (dict(delay="2"), "delay"),
])
def test_bad_arguments(kw, match):
    args = dict(total=10, label="x")
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        Progress(args.pop("total"), args.pop("label"), **args)


def test_docstring_examples_run():
    import doctest

    import hybridpd.sweeps.progress as mod

    failures, tried = doctest.testmod(mod)
    assert tried >= 3 and failures == 0
