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
                and action.option_strings):
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


def add_plant(p, *, xm=True, gamma=False, required=True, L_required=True):
    p.add_argument("--case", required=required, type=case_type, metavar="CASE",
                   help="collocated (the PD loop measures the secondary mass x2, the one it "
                        "pushes) or noncollocated (it measures the primary mass x1 through "
                        "the backlash; alias non-collocated)")
    p.add_argument("--mu", type=float, required=required, help="mass ratio m1/m2 (> 0)")
    p.add_argument("--m2", type=float, default=1.0, help="secondary mass m2 (> 0)")
    p.add_argument("--omega", type=float, required=required, help="reference frequency (> 0)")
    if gamma:
        g = p.add_mutually_exclusive_group(required=required)
        g.add_argument("--L", type=float, help="half clearance (> 0)")
        g.add_argument("--gamma", type=float, help="L / x10 (> 0)")
        p.add_argument("--x10", type=float, default=1.0,
                       help="amplitude of the primary mass's desired motion (> 0)")
    else:
        p.add_argument("--L", type=float, required=L_required, help="half clearance (> 0)")
    if xm:
        p.add_argument("--xm", type=float, required=True, help="reference amplitude (>= 0)")


def add_model(p, *, uses: str):
    """``--model FILE.toml`` and ``--list-params``; ``uses`` says how the command takes the
    file's parameters (e.g. ``"--set KEY VALUE sets them"``)."""
    p.add_argument("--model", default=None, metavar="FILE.toml",
                   help="mechanical model file (then the impact-pair options are not used). "
                        "Its parameters are its numeric entries, named by dotted TOML paths "
                        "(controller.kp, contact.0.restitution, system.masses.2, "
                        f"reference.omega, ...): --list-params lists them; {uses}")
    p.add_argument("--list-params", action="store_true",
                   help="with --model FILE.toml: print the file's parameters (dotted paths) "
                        "with their values, one per line (with --json: one object), and "
                        "exit 0")


def add_set(p):
    """``--set KEY VALUE`` (repeatable): a model file's entries set before the run."""
    p.add_argument("--set", nargs=2, action="append", default=None, metavar=("KEY", "VALUE"),
                   help="--model: set the file's numeric entry KEY (a dotted path, see "
                        "--list-params; a pattern controller.*.kp or a list a.b,c.d sets "
                        "every entry it matches) to VALUE first; repeatable")


def set_values(args) -> dict:
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

    values = set_values(args)
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
    from hybridpd.mechanics.params import ModelTemplate
    from hybridpd.plotting._common import describe_controllers

    return describe_controllers(ModelTemplate.load(args.model).with_values(set_values(args)))


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


def add_model_section(p, *, period_help="returns to the section per orbit (k of P^k)",
                      uses="--set KEY VALUE sets them"):
    """``--model``, ``--list-params`` and the options choosing a model file's section and
    orbits."""
    add_model(p, uses=uses)
    p.add_argument("--contact", type=int, default=0,
                   help="--model: 0-based contact whose impacts (or releases) define the "
                        "section")
    p.add_argument("--wall", type=int, choices=[-1, 1], default=None,
                   help="--model: +1 (hi) or -1 (lo) bound of the contact (default hi)")
    p.add_argument("--event", default="impact", choices=["impact", "release"],
                   help="--model: section on the contact's impacts, or on the ends of its "
                        "sticking phases (once per burst of impacts)")
    p.add_argument("--period", type=period_arg, default="auto", metavar="{auto,K}",
                   help=f"--model: {period_help}; 'auto' (default): the neighbours' or 1, "
                        "then every K <= 4 after which the simulated motion returns with "
                        "whole reference periods (the result says which K)")
    p.add_argument("--mode", default=None, metavar="MODE",
                   help="--model: the mode in which the section's guard fires, e.g. "
                        "'stick0+1+' when contact 0 releases while contact 1 is held "
                        "(default: the one the simulated motion takes)")
    p.add_argument("--periods", type=int, default=None,
                   help="--model: reference periods per orbit (default: any whole number)")


def period_arg(text: str):
    """``--period``: ``auto`` or a whole number >= 1 (argparse type)."""
    if text == "auto":
        return text
    try:
        k = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be 'auto' or an integer >= 1, got {text!r}") \
            from None
    if k < 1:
        raise argparse.ArgumentTypeError(f"must be 'auto' or an integer >= 1, got {k}")
    return k


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


def add_sweep(p, out=(".nc", ".zarr", ".npz"), what="the result", store=True,
              model_out=(".nc", ".zarr")):
    add_executor(p, default="serial")
    if store:
        p.add_argument("--store", default=None, metavar="DIR.zarr",
                       help="write the sweep to this Zarr store as chunks finish; a rerun "
                            "with the same arguments resumes from it")
    p.add_argument("--out", default=None, metavar="FILE",
                   help=f"write the result to this file, by suffix (impact pair: "
                        f"{_either(out)}; --model: {_either(model_out)}); draw it later with "
                        "'hybridpd plot FILE'")
    p.add_argument("--plot", default=None, metavar="IMAGE",
                   help=f"draw {what} to this .png, .pdf or .svg")
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    add_quiet(p)


def _either(suffixes) -> str:
    return suffixes[0] if len(suffixes) == 1 else (
        ", ".join(suffixes[:-1]) + " or " + suffixes[-1])


def add_executor(p, default="serial"):
    """``--executor``, ``--workers`` and ``--scheduler`` (see :func:`executor_of`)."""
    p.add_argument("--executor", default=None, choices=["serial", "processes", "dask"],
                   help="where the grid points run: in this process, a process pool, or a "
                        f"Dask cluster (dask.distributed) (default: {default}, or the "
                        "cluster of --scheduler / $DASK_SCHEDULER_ADDRESS)")
    p.add_argument("--workers", type=int, default=None,
                   help="worker count (default: all cores)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on the existing dask.distributed cluster of this scheduler "
                        "(tcp://host:8786; default $DASK_SCHEDULER_ADDRESS if set)")
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


def add_quiet(p):
    p.add_argument("--quiet", action="store_true",
                   help="no progress on stderr (by default a bar on a terminal, otherwise a "
                        "line every ~10 s)")


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
    from hybridpd.sweeps.labelled import SUFFIXES

    return _check(path, flag, allowed or SUFFIXES)


def _check(path, flag, allowed):
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.sweeps.labelled import check_suffix

    if path is None:
        return None
    try:
        check_suffix(path, flag, allowed)
    except ValueError:
        choice = _either(allowed)
        raise ValueError(f"{flag} must end in {choice} (what this command writes), got "
                         f"{str(path)!r}") from None
    return path


def save_figure(fig, path) -> None:
    """Write `fig` to `path` (format from the suffix), creating the folder."""
    # deferred import: loaded only when this runs, for start-up time
    from pathlib import Path

    from hybridpd.plotting.style import house_style

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with house_style():
        fig.savefig(path, dpi=300)


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
    check_out(args.out, allowed=(".nc", ".zarr"))
    check_image(args.plot)
