"""Number formatting shared by reports and figures."""
from __future__ import annotations


def pct(fraction) -> str:
    """A share in percent that never rounds to 0 % or 100 % when it is not exactly that.

    Examples
    --------
    >>> pct(0.5), pct(0.99999), pct(1e-5), pct(1.0)
    ('50.0%', '>99.9%', '<0.1%', '100.0%')
    """
    p = 100 * float(fraction)
    s = f"{p:.1f}%"
    if 0 < p < 0.05:
        s = "<0.1%"
    elif 99.95 <= p < 100:
        s = ">99.9%"
    return s
