"""Number formatting shared by reports and figures."""
from __future__ import annotations

__all__ = ["format_percent", "pct"]


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


def format_percent(part, whole=None, digits: int = 2) -> str:
    """A percentage that never rounds to 100 % or 0 % when some points differ.

    Parameters
    ----------
    part : int or float
        A count (with ``whole``) or a fraction in ``[0, 1]``.
    whole : int, optional
        Total count.
    digits : int
        Decimals shown.

    Examples
    --------
    >>> format_percent(9999, 10000), format_percent(99999, 100000), format_percent(1, 100000)
    ('99.99 %', '>99.99 %', '<0.01 %')
    >>> format_percent(0, 5), format_percent(5, 5), format_percent(0.25)
    ('0 %', '100 %', '25.00 %')
    """
    if whole is not None:
        if not (int(whole) == whole and whole > 0 and 0 <= part <= whole):
            raise ValueError(f"need 0 <= part <= whole with whole > 0, got {part!r}/{whole!r}")
        frac = part / whole
        exact0, exact1 = part == 0, part == whole
    else:
        frac = float(part)
        if not 0.0 <= frac <= 1.0:
            raise ValueError(f"part must be a fraction in [0, 1], got {part!r}")
        exact0, exact1 = frac == 0.0, frac == 1.0
    if exact0:
        return "0 %"
    if exact1:
        return "100 %"
    step = 10.0 ** -digits
    p = 100.0 * frac
    if round(p, digits) >= 100.0:
        return f">{100.0 - step:.{digits}f} %"
    if round(p, digits) <= 0.0:
        return f"<{step:.{digits}f} %"
    return f"{p:.{digits}f} %"
