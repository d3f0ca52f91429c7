"""Shared pieces of the command-line interface: the parser class, common options, errors,
exit statuses and the strict JSON writer."""
from __future__ import annotations

import argparse
import difflib
import math
import sys

#: Exit statuses of the commands (documented in the README's command-line section).
EXIT_OK = 0
EXIT_BAD_INPUT = 2
#: an infeasible design, or no periodic orbit (``hybridpd orbit``)
EXIT_INFEASIBLE = 3
EXIT_NO_ORBIT = 3
#: the run diverged: the state or the map overflowed, grew past the divergence bound or went
#: non-finite, or contacts closing at one instant had no joint impact (``simulate``)
EXIT_DIVERGED = 4
#: a simulation stopped before its end time at a bound of the run (``jump_limit``: the
#: ``--max-impacts`` bound; ``step_limit``: the bound on flow steps; ``zeno``: an accumulation
#: of jumps the automaton cannot continue past)
EXIT_STOPPED_EARLY = 5


class UsageError(Exception):
    """Bad command-line input (exit status 2)."""


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Keeps descriptions and epilogs as written and shows every non-trivial default."""

    def _get_help_string(self, action):
        text = action.help or ""
        default = action.default
        if (text and "%(default)" not in text and not action.required
                and default not in (None, False, argparse.SUPPRESS)
                and action.option_strings and "default" not in text):
            text += " (default: %(default)s)"
        return text


CASES = {"collocated": "collocated", "noncollocated": "noncollocated",
         "non-collocated": "noncollocated"}


def case_type(text: str) -> str:
    """``--case`` values: the paper's spelling ``non-collocated`` is accepted as an alias."""
    key = text.strip().lower()
    if key not in CASES:
        raise argparse.ArgumentTypeError(
            f"invalid case {text!r}: use collocated or noncollocated (alias non-collocated)")
    return CASES[key]


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (status 2) and name unknown flags."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        # Abbreviations would let a typo silently match another option.
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message):
        # argparse prints the whole usage and exits; the project wants one line and status 2.
        raise UsageError(message)

    def parse_known_args(self, args=None, namespace=None):
        # Unknown flags are reported before argparse's "X is required" (which would
        # otherwise hide a misspelt required option such as --Kp).
        args = list(sys.argv[1:] if args is None else args)
        for tok in args:
            if tok == "--":
                break
            if self._subparsers is not None and not tok.startswith("-"):
                break  # the sub-command's own flags are checked by its parser
            if tok.startswith("--"):
                flag = tok.split("=", 1)[0]
                if flag not in self._option_string_actions:
                    raise UsageError(unknown_flag_message(flag, self._option_string_actions))
        return super().parse_known_args(args, namespace)


def unknown_flag_message(flag: str, known) -> str:
    """``unknown option --Kp (did you mean --kp?)``."""
    options = sorted(o for o in known if o.startswith("--"))
    lowered = {o.lower(): o for o in options}
    guess = lowered.get(flag.lower())
    if guess is None:
        close = difflib.get_close_matches(flag, options, n=1, cutoff=0.6)
        guess = close[0] if close else None
    hint = f" (did you mean {guess}?)" if guess else ""
    return f"unknown option {flag}{hint}"


#: The impact pair's options, in the order the help lists them.
PAIR_OPTIONS = ("case", "mu", "m2", "omega", "L", "gamma", "x10", "xm", "e", "kp", "kv", "n")

#: The help text of each impact-pair option, the same in every command (CONVENTIONS.md).
PAIR_HELP = {
    "case": ("collocated (the PD loop measures the secondary mass x2, the one it pushes) or "
             "noncollocated (it measures the primary mass x1 through the backlash; alias "
             "non-collocated)"),
    "mu": "mass ratio mu = m1 / m2 (> 0)",
    "m2": "secondary mass m2 (> 0; default 1)",
    "omega": "reference frequency omega of xd = xm cos(omega t) (> 0, rad per time unit)",
    "L": "half clearance L (> 0): the masses touch at |x1 - x2| = L",
    "gamma": "clearance ratio gamma = L / x10 (> 0)",
    "x10": ("amplitude x10 of the primary mass's desired motion, a triangle wave between "
            "+x10 and -x10 (> 0; default 1)"),
    "xm": "reference amplitude xm of xd = xm cos(omega t) (>= 0)",
    "e": "restitution coefficient e of Newton's impact law, in [0, 1]",
    "kp": "proportional gain kp (> 0)",
    "kv": "derivative gain kv (> 0)",
    "n": "odd order n of the symmetric orbit (period n T, T = 2 pi / omega)",
}

#: What a grid or a list of values adds to the help of a pair option.
GRID_HELP = ": a grid axis of NUM points from MIN to MAX"
LIST_HELP = ": one or more values"

_PAIR_REQUIRED = ("case", "mu", "omega", "L", "gamma", "e", "kp", "kv", "xm")


def add_pair(p, *, names=("case", "mu", "m2", "omega", "L", "gamma", "x10", "e", "kp", "kv",
                          "n"),
             required=(), clearance: str = "either", grid=(), many=(), m2=1.0, x10=1.0):
    """The impact pair's options (:data:`PAIR_OPTIONS`), declared here once for every command.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    names : tuple of str
        The options the command takes, a subset of :data:`PAIR_OPTIONS`.
    required : bool or tuple of str
        The options argparse requires (``True``: all of them but ``m2``, ``x10`` and ``n``);
        the others default to None (or to `m2`, `x10`, 1 for ``n``) and the command checks
        them, e.g. because ``--model`` replaces them.
    clearance : {"either", "both"}
        ``"either"``: ``--L`` and ``--gamma`` exclude each other; ``"both"``: both may be
        given (the command checks that they agree).
    grid, many : tuple of str
        Options taking ``MIN MAX NUM`` (a grid axis) or one or more values instead of one.
    m2, x10 : float or None
        Defaults of ``--m2`` and ``--x10`` (None where the command must see whether they
        were given).

    Examples
    --------
    >>> p = Parser(prog="demo")
    >>> add_pair(p, names=("e", "kp"), many=("e",))
    >>> p.parse_args(["--e", "0.1", "0.5", "--kp", "10"])
    Namespace(e=[0.1, 0.5], kp=10.0)
    """
    unknown = sorted(set(names) - set(PAIR_OPTIONS))
    if unknown:
        raise ValueError(f"names: not impact-pair options: {', '.join(unknown)}")
    if clearance not in ("either", "both"):
        raise ValueError(f"clearance must be 'either' or 'both', got {clearance!r}")
    if required is True:
        required = _PAIR_REQUIRED
    exclusive = clearance == "either" and "L" in names and "gamma" in names
    group = None
    if exclusive:
        group = p.add_mutually_exclusive_group(
            required="L" in required or "gamma" in required)
    for name in PAIR_OPTIONS:
        if name not in names:
            continue
        target = group if exclusive and name in ("L", "gamma") else p
        kw = {"help": PAIR_HELP[name], "default": None, "type": float}
        if name == "case":
            kw.update(type=case_type, metavar="CASE")
        elif name == "n":
            kw.update(type=int, default=1)
        elif name == "m2":
            kw["default"] = m2
        elif name == "x10":
            kw["default"] = x10
        if name in grid:
            kw.update(nargs=3, metavar=("MIN", "MAX", "NUM"), help=kw["help"] + GRID_HELP)
        elif name in many:
            kw.update(nargs="+", help=kw["help"] + LIST_HELP)
        if name in required and target is p:
            kw["required"] = True
        target.add_argument(f"--{name}", **kw)


def add_model(p, *, set_option: bool = True, section: bool = True):
    """The model-file options: ``--model FILE.toml``, ``--list-params``, ``--set KEY VALUE``
    (with `set_option`) and the options choosing a model file's section and orbits (with
    `section`: ``--contact``, ``--wall``, ``--event``, ``--phase``, ``--period``, ``--mode``,
    ``--periods``), declared here once for every command.

    Examples
    --------
    >>> p = Parser(prog="demo")
    >>> add_model(p, section=False)
    >>> p.parse_args(["--model", "m.toml", "--set", "controller.kp", "2"]).set
    [['controller.kp', '2']]
    """
    p.add_argument("--model", default=None, metavar="FILE.toml",
                   help="mechanical model file (then the impact-pair options are not used). "
                        "Its parameters are its numeric entries, named by dotted TOML paths "
                        "(controller.kp, contact.0.restitution, system.masses.2, "
                        "reference.omega, ...): --list-params lists them")
    p.add_argument("--list-params", action="store_true",
                   help="with --model FILE.toml: print the file's parameters (dotted paths) "
                        "with their values, one per line (with --json: one object), and "
                        "exit 0")
    if set_option:
        p.add_argument("--set", nargs=2, action="append", default=None,
                       metavar=("KEY", "VALUE"),
                       help="--model: set the file's numeric entry KEY (a dotted path, see "
                            "--list-params; a pattern controller.*.kp or a list a.b,c.d sets "
                            "every entry it matches) to VALUE first; repeatable")
    if section:
        _add_section(p)


def _add_section(p):
    p.add_argument("--contact", type=int, default=0,
                   help="--model: 0-based contact whose impacts (or releases) define an "
                        "event section")
    p.add_argument("--wall", type=int, choices=[-1, 1], default=None,
                   help="--model: +1 (hi) or -1 (lo) bound of the contact (default hi)")
    p.add_argument("--event", default="auto",
                   choices=["auto", "stroboscopic", "impact", "release"],
                   help="--model: the section. 'auto' (default): the stroboscopic one (the "
                        "state at one phase of the reference, one common period of the "
                        "reference and the sampling later) when the reference is periodic, "
                        "else the event section the simulated motion crosses (reported); "
                        "'impact': the contact's impacts; 'release': the ends of its "
                        "sticking phases (once per burst of impacts)")
    p.add_argument("--phase", type=float, default=None, metavar="PHI0",
                   help="--model: the phase phi0 of the stroboscopic section (time units; "
                        "default: chosen where the simulated motion has no jump other than "
                        "a sample nearby, in the free mode if it has one)")
    p.add_argument("--period", type=period_arg, default="auto", metavar="{auto,K}",
                   help="--model: returns to the section per orbit, the k of the map P^k "
                        "the command works with; 'auto' (default): the neighbours' or 1, "
                        "then every K <= 4 after which the simulated motion returns with "
                        "whole reference periods (the result says which K)")
    p.add_argument("--mode", default=None, metavar="MODE",
                   help="--model: the mode in which the section's guard fires, e.g. "
                        "'stick0+1+' when contact 0 releases while contact 1 is held "
                        "(default: the one the simulated motion takes)")
    p.add_argument("--periods", type=int, default=None,
                   help="--model: reference periods per orbit (default: any whole number)")


def set_option_values(args) -> dict:
    """``{path: value}`` of the ``--set`` options (ValueError for a VALUE that is no
    number)."""
    values = {}
    for key, val in getattr(args, "set", None) or ():
        try:
            values[key] = float(val)
        except ValueError:
            raise ValueError(f"--set {key}: VALUE must be a number, got {val!r}") from None
    return values


def model_of(args):
    """The model of ``--model`` with the ``--set`` values (each path checked first)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.mechanics.params import ModelTemplate

    values = set_option_values(args)
    if not values:
        # deferred import: loaded only when this runs, for start-up time
        from hybridpd.mechanics.modelfile import load_model

        return load_model(args.model)
    template = ModelTemplate.load(args.model)
    template.check(*values)
    return template.model(values)


def controllers_of(args) -> str:
    """The controllers of ``--model`` (with the ``--set`` values) in words, for titles and
    for the ``controllers`` entry of a result's metadata (figures drawn later name them)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.mechanics.modelfile import describe_controllers
    from hybridpd.mechanics.params import ModelTemplate

    return describe_controllers(ModelTemplate.load(args.model).with_values(set_option_values(args)))


def stamp_controllers(result, args):
    """A copy of the (dataclass) `result` whose ``metadata`` also names the controllers of
    ``--model``, so that a figure drawn from its file later names them too."""
    import dataclasses

    return dataclasses.replace(result, metadata={"controllers": controllers_of(args),
                                                 **result.metadata})


def list_params(args) -> int:
    """``--list-params``: the numeric entries of ``--model`` (dotted path and value), one per
    line, or one JSON object ``{"model": FILE, "parameters": {path: value}}``."""
    if args.model is None:
        raise UsageError("--list-params needs --model FILE.toml (the impact pair's "
                         "parameters are its options: see --help)")
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.mechanics.params import ModelTemplate

    paths = ModelTemplate.load(args.model).paths
    if getattr(args, "json", False):
        print_json({"model": str(args.model), "parameters": paths})
        return EXIT_OK
    for path, value in paths.items():
        print(f"{path} = {value!r}")
    return EXIT_OK


def require(args, *names) -> None:
    """Refuse (UsageError) missing options that argparse cannot require (they are optional
    with ``--list-params``)."""
    missing = [f"--{n.replace('_', '-')}" for n in names if getattr(args, n) is None]
    if missing:
        raise UsageError(f"the following arguments are required: {', '.join(missing)}")


def _auto_or_int(text: str, lo: int, hi: int | None):
    """``auto`` or a whole number in ``[lo, hi]`` (``hi`` None: no upper end), else the
    argparse error naming the range."""
    if text == "auto":
        return text
    rng = f"in [{lo}, {hi}]" if hi is not None else f">= {lo}"
    try:
        k = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be 'auto' or an integer {rng}, got "
                                         f"{text!r}") from None
    if k < lo or (hi is not None and k > hi):
        raise argparse.ArgumentTypeError(f"must be 'auto' or an integer {rng}, got {k}")
    return k


def depth_arg(text: str):
    """``--depth``: ``auto`` or a whole number in [0, 16] (argparse type)."""
    return _auto_or_int(text, 0, 16)


def period_arg(text: str):
    """``--period``: ``auto`` or a whole number >= 1 (argparse type)."""
    return _auto_or_int(text, 1, None)


def clearance(args):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.model import check_positive

    x10 = check_positive("x10", args.x10)
    if args.L is not None:
        return check_positive("L", args.L), x10
    return check_positive("gamma", args.gamma) * x10, x10


def command(sub, name: str, *, help: str, description: str, example: str,
            notes: str | None = None):
    """A sub-command parser with a one-line ``help``, a paragraph and an example epilog
    (followed by ``notes``, e.g. the exit statuses, kept as written)."""
    import textwrap

    epilog = "example:\n  " + example + ("\n\n" + notes if notes else "")
    return sub.add_parser(name, help=help, description=textwrap.fill(description, 88),
                          epilog=epilog)


JSON_HELP = ("print one JSON object on stdout instead of the summary (strict JSON: null for "
             "a number that is not finite)")


def json_ready(obj):
    """`obj` with every non-finite float replaced by None, NumPy scalars and arrays turned
    into Python numbers and lists, tuples into lists: what strict JSON can hold.

    Examples
    --------
    >>> import numpy as np
    >>> json_ready({"a": float("nan"), "b": np.array([1.0, np.inf]), "c": (np.int64(2),)})
    {'a': None, 'b': [1.0, None], 'c': [2]}
    """
    if isinstance(obj, dict):
        return {str(k): json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v) for v in obj]
    if isinstance(obj, bool) or obj is None or isinstance(obj, str):
        return obj
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, int):
        return obj
    tolist = getattr(obj, "tolist", None)   # NumPy scalars and arrays
    if tolist is not None:
        return json_ready(tolist())
    if isinstance(obj, complex):
        return [json_ready(obj.real), json_ready(obj.imag)]
    return str(obj)


def dumps_json(obj) -> str:
    """Strict JSON text of `obj` (:func:`json_ready`; never NaN or Infinity)."""
    import json

    return json.dumps(json_ready(obj), allow_nan=False)


def print_json(obj) -> None:
    """``--json``: one strict JSON object on stdout (:func:`dumps_json`)."""
    print(dumps_json(obj))


def add_output(p, *, out=None, model_out=None, what: str = "the result", plot=None,
               store: bool = False, json: bool = True):
    """The output and figure options, declared here once for every command: ``--store``
    (with `store`), ``--out FILE`` (with `out`, the suffixes the impact pair writes, and
    `model_out`, those ``--model`` writes), ``--plot IMAGE`` (with `plot`, what the figure
    shows) and ``--json`` (with `json`).

    Examples
    --------
    >>> p = Parser(prog="demo")
    >>> add_output(p, out=(".nc",), plot="the map")
    >>> p.parse_args(["--out", "a.nc", "--json"])
    Namespace(out='a.nc', plot=None, json=True)
    """
    if store:
        p.add_argument("--store", default=None, metavar="DIR.zarr",
                       help="write the sweep to this Zarr store as chunks finish; a rerun "
                            "with the same arguments resumes from it")
    if out is not None:
        where = (f"impact pair: {_either(out)}; --model: {_either(model_out)}"
                 if model_out is not None else _either(out))
        p.add_argument("--out", default=None, metavar="FILE",
                       help=f"write {what} to this file, by suffix ({where}); draw it later "
                            "with 'hybridpd plot FILE'")
    if plot is not None:
        p.add_argument("--plot", default=None, metavar="IMAGE",
                       help=f"draw {plot} to this {_either(IMAGE_SUFFIXES)}")
    if json:
        p.add_argument("--json", action="store_true", help=JSON_HELP)


def _either(suffixes) -> str:
    return suffixes[0] if len(suffixes) == 1 else (
        ", ".join(suffixes[:-1]) + " or " + suffixes[-1])


def add_grid_axis(p, flag: str, *, names: bool = True, num: bool = True, word: str = "NAME",
                  help: str | None = None, required: bool = False) -> None:
    """One grid axis in the one shape every command uses: ``flag NAME MIN MAX NUM``, without
    ``NAME`` where the command knows the axis (``names=False``) and without ``NUM`` where it
    chooses the points itself (``num=False``). ``word`` names ``NAME`` in the help (``KEY``
    for a model file's entry); :func:`grid_axis` reads the tokens back.

    Examples
    --------
    >>> p = Parser(prog="demo")
    >>> add_grid_axis(p, "--x", word="KEY")
    >>> add_grid_axis(p, "--y", word="KEY")
    >>> args = p.parse_args(["--x", "controller.kp", "5", "60", "8", "--y", "a.b", "1", "2", "3"])
    >>> grid_axis("--x", args.x), grid_axis("--y", args.y)
    (('controller.kp', 5.0, 60.0, 8), ('a.b', 1.0, 2.0, 3))
    """
    mv = ((word,) if names else ()) + ("MIN", "MAX") + (("NUM",) if num else ())
    p.add_argument(flag, nargs=len(mv), default=None, required=required, metavar=mv,
                   help=help)


def grid_axis(flag: str, tokens, *, names: bool = True, num: bool = True) -> tuple:
    """``(NAME, MIN, MAX, NUM)`` (``NAME`` left out with ``names=False``, ``NUM`` with
    ``num=False``) of the tokens of a flag declared by :func:`add_grid_axis`: ``MIN`` and
    ``MAX`` as floats, ``NUM`` as an int (``ValueError`` naming the flag otherwise; the range
    itself is checked by the analysis that takes it)."""
    tokens = list(tokens)
    head, rest = (tokens[:1], tokens[1:]) if names else ([], tokens)
    want = 3 if num else 2
    if len(rest) != want:
        shape = " ".join((("NAME",) if names else ()) + ("MIN", "MAX") + (("NUM",) if num else ()))
        raise ValueError(f"{flag} must be {shape}, got {' '.join(map(str, tokens))!r}")
    try:
        lo, hi = float(rest[0]), float(rest[1])
    except ValueError:
        raise ValueError(f"{flag} MIN and MAX must be numbers, got {rest[0]!r} {rest[1]!r}") \
            from None
    if not num:
        return (*head, lo, hi)
    try:
        n = float(rest[2])
    except ValueError:
        n = math.nan
    if not (math.isfinite(n) and n == int(n)):
        raise ValueError(f"{flag} NUM must be an integer, got {rest[2]!r}")
    return (*head, lo, hi, int(n))


def add_max_period(p, default: int, what: str = "largest period of P detected") -> None:
    """``--max-period K``: the one declaration; each command passes its own default."""
    p.add_argument("--max-period", type=int, default=default,
                   help=f"{what} (default {default})")


def check_max_period(args) -> None:
    """``--max-period`` within ``[1, 64]`` (``ValueError`` naming it)."""
    if not 1 <= args.max_period <= 64:
        raise ValueError(f"--max-period must be in [1, 64], got {args.max_period}")


def add_executor(p, default: str = "serial", *, quiet: bool = True):
    """The executor options, declared here once for every command: ``--executor``,
    ``--workers``, ``--scheduler`` (see :func:`executor_of`) and, with `quiet`, ``--quiet``.

    Examples
    --------
    >>> p = Parser(prog="demo")
    >>> add_executor(p, default="processes")
    >>> executor_of(p.parse_args(["--executor", "serial"]))
    'serial'
    """
    p.add_argument("--executor", default=None, choices=["serial", "processes", "dask"],
                   help="where the grid points run: in this process, a process pool, or a "
                        f"Dask cluster (dask.distributed) (default: {default}, or the "
                        "cluster of --scheduler / $DASK_SCHEDULER_ADDRESS)")
    p.add_argument("--workers", type=int, default=None,
                   help="worker count (default: all cores)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on the existing dask.distributed cluster of this scheduler "
                        "(tcp://host:8786; default $DASK_SCHEDULER_ADDRESS if set)")
    if quiet:
        p.add_argument("--quiet", action="store_true",
                       help="no progress on stderr (by default a bar on a terminal, "
                            "otherwise a line every ~10 s)")
    p.set_defaults(_executor_default=default)


def executor_of(args):
    """The executor of a sweeping command: ``--scheduler``, else ``$DASK_SCHEDULER_ADDRESS``
    (unless ``--executor`` chose another), else ``--executor`` or the command's default.

    A scheduler address is what :func:`hybridpd.sweeps.sweep.run_sweep` takes as executor.
    """
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.executors import check_scheduler_address, scheduler_from_env

    chosen = getattr(args, "executor", None)
    if args.scheduler is not None:
        if chosen not in (None, "dask"):
            raise UsageError(f"--scheduler runs on a Dask cluster: it cannot be combined with "
                             f"--executor {chosen}")
        return check_scheduler_address(args.scheduler)
    if chosen in (None, "dask"):
        env = scheduler_from_env()
        if env is not None:
            return env
    return chosen or getattr(args, "_executor_default", "serial")


def progress_wanted(args) -> bool:
    # The reporter picks a bar (terminal) or plain lines (logs); only --quiet silences it.
    return not getattr(args, "quiet", False)


#: Suffixes of the images that --plot and ``hybridpd plot --out`` write.
IMAGE_SUFFIXES = (".png", ".pdf", ".svg")


def check_image(path, flag: str = "--plot"):
    """Refuse (ValueError, before any computation) an image path matplotlib is not asked to
    write: only :data:`IMAGE_SUFFIXES`."""
    return _check(path, flag, IMAGE_SUFFIXES)


def check_out(path, flag: str = "--out", allowed=None):
    """Refuse (ValueError, before any computation) a result path whose suffix cannot be
    written (default: ``.nc``, ``.zarr``, ``.npz``)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd._results import SUFFIXES

    return _check(path, flag, allowed or SUFFIXES)


def _check(path, flag, allowed):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd._results import check_suffix

    if path is None:
        return None
    try:
        check_suffix(path, flag, allowed)
    except ValueError:
        choice = _either(allowed)
        raise ValueError(f"{flag} must end in {choice} (what this command writes), got "
                         f"{str(path)!r}") from None
    return path


def write_figure(fig, path) -> None:
    """Write `fig` to the one image `path` (its format from the suffix) in the house style,
    creating the folder (:func:`hybridpd.plotting.style.save_figure` with that format)."""
    # deferred import: loaded only when this runs, for start-up time
    from pathlib import Path

    from hybridpd.plotting.style import house_style, save_figure

    with house_style():
        save_figure(fig, path, formats=(Path(path).suffix.lstrip("."),), dpi=300)


def check_pair_command(args, pair_options, outputs: bool = True) -> tuple:
    """Check an impact-pair command (no ``--model``): the pair's options are all given and,
    with ``outputs``, the output paths ``--out`` and ``--plot`` are well formed. Returns the
    clearance ``(L, x10)``; runs before anything is computed.
    """
    missing = [f"--{k}" for k in pair_options if getattr(args, k) is None]
    if args.L is None and args.gamma is None:
        missing.append("--L or --gamma")
    if missing:
        raise UsageError(f"the following arguments are required: {', '.join(missing)} "
                         "(or give --model FILE.toml)")
    if outputs:
        check_out(args.out)
        check_image(args.plot)
    return clearance(args)


def check_model_command(args, pair_options, hint: str, axes: str | None = None) -> None:
    """Refuse impact-pair options and malformed output paths of a ``--model`` command.

    ``pair_options`` are the attribute names of the pair's options, ``hint`` says what to use
    instead, and ``axes`` (e.g. ``"KEY"``) makes ``--x``/``--y`` required. Runs before
    anything is computed.
    """
    given = [f"--{k}" for k in pair_options if getattr(args, k) is not None]
    if given:
        raise UsageError(f"{', '.join(given)}: impact-pair options, not used with --model "
                         f"({hint})")
    if axes is not None and (args.x is None or args.y is None):
        raise UsageError(f"--model needs --x {axes} MIN MAX NUM and --y {axes} MIN MAX NUM")
    check_out(args.out)
    check_image(args.plot)
