"""``hybridpd explore``: the region map as a page you click, served on this machine."""
from __future__ import annotations

from hybridpd.cli import _common as cli
from hybridpd.cli._common import UsageError, command

DESCRIPTION = ("Serves a page on 127.0.0.1 mapping where the impact pair's symmetric orbit "
               "exists and is stable over the gains (kp, kv), with controls for the case, "
               "e, mu, m2, gamma, omega, n and the box of gains. A click on the map selects "
               "the gains and shows their orbit over one period (time series, phase "
               "portrait, impacts), its multipliers on the unit circle with the spectral "
               "radius and the viability margin; on demand the basin slice through the orbit "
               "and the branch followed along kp or kv with its events. The page's state is "
               "in its URL (share it to share the view); every panel saves its figure and "
               "its data. The options give where the page starts (default collocated, "
               "e = 0.5, mu = 0.1, m2 = 1, gamma = 0.75, omega = 5, kp = 10, kv = 20, n = 1). Needs the extra "
               "hybridpd[explore] (Panel, Bokeh).")

NOTES = """\
exit status:
  0  the server was stopped (Ctrl-C)
  2  bad input (one line on stderr), or Panel/Bokeh not installed"""


def register(sub):
    p = command(sub, "explore", help="the region map as a page you click (a local web page)",
                description=DESCRIPTION,
                example=("hybridpd explore --case noncollocated --e 0.1 --kp 12 --kv 25\n"
                         "  hybridpd explore --no-browser --port 5006\n"
                         "  hybridpd explore --model examples/models/robot_joint_pd.toml "
                         "--x controller.kp 5 60 8 --y controller.kv 1 20 8"),
                notes=NOTES)
    p.add_argument("--port", type=int, default=0,
                   help="TCP port on 127.0.0.1 (default 0: a free one, printed)")
    p.add_argument("--no-browser", action="store_true",
                   help="do not open the page in the web browser")
    # the pair's options as every command declares them; the page's own defaults (e = 0.5,
    # mu = 0.1, gamma = 0.75, omega = 5, kp = 10, kv = 20, n = 1) fill in what is not given
    cli.add_pair(p, names=("case", "mu", "m2", "omega", "gamma", "e", "kp", "kv", "n"),
                 m2=None)
    p.add_argument("--box", type=float, nargs=4, default=None,
                   metavar=("KP_MIN", "KP_MAX", "KV_MIN", "KV_MAX"),
                   help="the box of gains mapped (default 0.1 50 0.1 50)")
    p.add_argument("--num", type=int, default=None,
                   help="grid points per axis of the map, 2 to 401 (default 201)")
    cli.add_model(p, set_option=False)
    cli.add_grid_axis(p, "--x", word="KEY",
                      help="--model: first axis of the map, a numeric entry of the file (dotted "
                           "path, as hybridpd regions --model takes it) on NUM points from MIN "
                           "to MAX")
    cli.add_grid_axis(p, "--y", word="KEY", help="--model: second axis of the map, as --x")
    p.set_defaults(func=run)


def model_axis(name: str, tokens) -> tuple:
    """``--x``/``--y``: ``(KEY, MIN, MAX, NUM)`` from ``KEY MIN MAX NUM`` (at least 2 points).

    Examples
    --------
    >>> model_axis("x", ["controller.kp", "5", "60", "8"])
    ('controller.kp', 5.0, 60.0, 8)
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.model import check_axis

    key, lo, hi, num = cli.grid_axis(f"--{name}", tokens)
    xs = check_axis(f"--{name}", (lo, hi, num), min_num=2)
    return (key, float(xs[0]), float(xs[-1]), len(xs))


def _run_model(args) -> int:
    # (--n is left out: it defaults to 1, so it always reads as given)
    pair = [f"--{k}" for k in ("case", "e", "mu", "m2", "gamma", "omega", "kp", "kv", "box",
                               "num") if getattr(args, k) is not None]
    if pair:
        raise UsageError(f"{', '.join(pair)}: impact-pair options, not used with --model "
                         "(map the file's entries with --x and --y)")
    if args.x is None or args.y is None:
        raise UsageError("--model needs --x KEY MIN MAX NUM and --y KEY MIN MAX NUM")
    x, y = model_axis("x", args.x), model_axis("y", args.y)
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.model_regions import template_of

    template_of(args.model).check(x[0], y[0])    # the file loads and has both entries
    section = {k: getattr(args, k) for k in ("contact", "wall", "event", "period", "periods",
                                             "mode", "phase")}
    _need_panel()
    # deferred import: panel and the page load only when the server starts
    from hybridpd.explore.model_app import model_app
    from hybridpd.explore.server import serve

    serve(args.port, open_browser=not args.no_browser,
          app=lambda: model_app(args.model, x, y, section))
    return 0


def _need_panel():
    # found, not imported: Panel loads later, after the first map's process is forked
    from importlib.util import find_spec

    for name in ("bokeh", "panel"):
        if find_spec(name) is None:
            raise UsageError(f"the explorer needs Panel and Bokeh ({name} is missing): "
                             "pip install 'hybridpd[explore]'")


def start_state(args):
    """The page's starting state from the options (``ValueError`` naming a bad one)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.explore.state import PairState

    fields = {k: getattr(args, k) for k in ("case", "e", "mu", "m2", "gamma", "omega", "n",
                                             "kp", "kv", "num")
              if getattr(args, k) is not None}
    if args.box is not None:
        fields.update(zip(("kp_min", "kp_max", "kv_min", "kv_max"), args.box))
    return PairState(**fields)


def run(args) -> int:
    if not 0 <= args.port <= 65535:
        raise ValueError(f"--port must be an integer in [0, 65535], got {args.port}")
    if args.model is not None:
        return _run_model(args)
    if args.x is not None or args.y is not None:
        raise UsageError("--x and --y need --model FILE.toml (the pair's map is over kp, kv)")
    base = start_state(args)
    _need_panel()
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.explore.state import warm_map

    # forked before Panel loads: the first map is computed while the server starts
    first_map = warm_map(base)
    # deferred import: panel and the page load only when the server starts
    from hybridpd.explore.app import pair_app, warm_up
    from hybridpd.explore.server import serve

    warm = warm_up(base, first_map)    # while the server starts and the browser loads it
    serve(args.port, open_browser=not args.no_browser, app=lambda: pair_app(base, warm))
    return 0
