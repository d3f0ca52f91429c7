"""The house style of every hybridpd figure, for print.

Figures are drawn at their final size: :data:`SINGLE` (3.5 in) or :data:`DOUBLE` (7.2 in) wide,
at most :data:`MAX_HEIGHT` (9 in) high, with no text under :data:`MIN_FONT` (7 pt) at that size.
Colours are Okabe & Ito's colour-blind-safe palette, always with a second encoding (line style,
marker or hatch: :data:`SERIES`, :data:`HATCHES`), so that no two legend entries differ by colour
alone. Axis labels carry units (:func:`axis_label`); the package fixes no unit system, so they
are named by dimension (length, time, mass, force).

The style sheet ``paper.mplstyle`` beside this module is applied with
:func:`house_style` (an ``rc_context``) inside each plotting function, never globally:
importing hybridpd changes no matplotlib setting.
"""
from __future__ import annotations

import functools
from pathlib import Path

__all__ = ["DOUBLE", "HATCHES", "MAX_HEIGHT", "MIN_FONT", "OKABE_ITO", "SERIES", "SINGLE",
           "STYLE", "axis_label", "house_figure", "house_style", "save_figure", "series",
           "styled"]

#: The style sheet.
STYLE = Path(__file__).with_name("paper.mplstyle")
#: Print widths (inches): one column, two columns; the largest height.
SINGLE, DOUBLE, MAX_HEIGHT = 3.5, 7.2, 9.0
#: Smallest text size (points) at the saved size.
MIN_FONT = 7.0

#: Okabe & Ito's palette.
OKABE_ITO = {"black": "#000000", "orange": "#E69F00", "sky blue": "#56B4E9",
             "bluish green": "#009E73", "yellow": "#F0E442", "blue": "#0072B2",
             "vermillion": "#D55E00", "reddish purple": "#CC79A7"}

#: One style per series (e.g. per restitution coefficient): colour, line style and marker all
#: differ, so the series stay apart in grey-scale and under any colour-vision deficiency.
SERIES = (
    dict(color="#0072B2", ls="-", marker="o"),
    dict(color="#D55E00", ls="--", marker="s"),
    dict(color="#009E73", ls="-.", marker="^"),
    dict(color="#CC79A7", ls=":", marker="D"),
    dict(color="#000000", ls=(0, (5, 1, 1, 1, 1, 1)), marker="v"),
    dict(color="#E69F00", ls=(0, (1, 1)), marker="P"),
)

#: Hatches for filled areas beside a plain fill.
HATCHES = ("", "////", "\\\\\\\\", "xxxx", "....", "||||", "----", "++++")

_UNITS = {
    "kp": r"$k_p$ (force/length)", "kv": r"$k_v$ (force$\cdot$time/length)",
    "kp/m2": r"$k_p/m_2$ (1/time$^2$, per unit $m_2$)",
    "kv/m2": r"$k_v/m_2$ (1/time, per unit $m_2$)",
    "m2": r"$m_2$ (mass)", "mu": r"$\mu = m_1/m_2$ (1)", "gamma": r"$\gamma = L/x_{10}$ (1)",
    "e": "$e$ (1)", "omega": r"$\omega$ (rad/time)", "L": "$L$ (length)",
    "x10": "$x_{10}$ (length)", "xm": "$x_m$ (length)", "t": "$t$ (time)",
    "x1": "$x_1$ (length)", "y1": "$y_1$ (length/time)", "x2": "$x_2$ (length)",
    "y2": "$y_2$ (length/time)", "n": "$n$ (1)"}


def axis_label(name: str) -> str:
    """The axis label of a quantity: its symbol and unit; a model file's entry (a dotted
    path) in the file's own units, any other name as it is.

    Examples
    --------
    >>> from hybridpd.plotting.style import axis_label
    >>> axis_label("kp")
    '$k_p$ (force/length)'
    >>> axis_label("controller.kv")
    'controller.kv (model units)'
    """
    if name in _UNITS:
        return _UNITS[name]
    return f"{name} (model units)" if "." in name else name


def series(k: int) -> dict:
    """Colour, line style and marker of series ``k`` (cycling through :data:`SERIES`)."""
    return dict(SERIES[int(k) % len(SERIES)])


def house_style():
    """A context manager applying ``paper.mplstyle`` (``matplotlib.rc_context``)."""
    import matplotlib

    return matplotlib.rc_context(fname=str(STYLE))


def styled(fn):
    """Decorator: run a plotting function inside :func:`house_style`."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with house_style():
            return fn(*args, **kwargs)
    return wrapper


def house_figure(width="double", height=3.0):
    """A constrained-layout Figure at its print size (no pyplot, no global state).

    Parameters
    ----------
    width : {"single", "double"} or float
        ``"single"`` (3.5 in), ``"double"`` (7.2 in) or inches.
    height : float
        Inches, at most :data:`MAX_HEIGHT`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    w = {"single": SINGLE, "double": DOUBLE}.get(width, width)
    try:
        w = float(w)
    except (TypeError, ValueError):
        raise ValueError(f"width must be 'single', 'double' or inches, got {width!r}") from None
    if not 0 < w <= DOUBLE or not 0 < float(height) <= MAX_HEIGHT:
        raise ValueError(f"figure size must be 0 < width <= {DOUBLE} and 0 < height <= "
                         f"{MAX_HEIGHT} in, got {w} x {height}")
    with house_style():
        return Figure(figsize=(w, float(height)), layout="constrained")


def save_figure(fig, path, *, formats=("png", "pdf"), dpi=300) -> list:
    """Write ``fig`` at its size, PNG at ``dpi`` and PDF (one file per format, the suffix of
    ``path`` replaced); returns the paths written."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    out = []
    for fmt in formats:
        p = path.with_suffix(f".{fmt}")
        fig.savefig(p, dpi=dpi)
        out.append(p)
    return out
