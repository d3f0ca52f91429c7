"""``hybridpd explore``: the region map of the impact pair as a page you click.

The page (HoloViz Panel and Bokeh, the extra ``hybridpd[explore]``) maps where the symmetric
orbit exists and is stable over the gains ``(kp, kv)``; a click selects gains and shows their
orbit over one period, its multipliers and viability margin, and on demand the basin slice
and a branch followed along ``kp`` or ``kv``. The state is in the page's URL. From a shell:
``hybridpd explore`` (see ``hybridpd explore --help``); from Python this package is callable,
``hp.explore(e=0.1, kp=12)`` returns the page for a notebook, and :func:`serve` serves it.

With ``--model FILE.toml`` the page maps two entries of a model file instead and shows a
clicked cell's orbit, multipliers and basin slice (:mod:`.model_app`).

Modules: :mod:`.state` (the state, its URL and the computations, no web library),
:mod:`.figures` (the saved figures and data), :mod:`.app` (the pair's page),
:mod:`.model_app` (a model file's page), :mod:`.server`.
Nothing of Panel or Bokeh loads before a page is built.

Examples
--------
>>> from hybridpd.explore.state import PairState, pair_orbit
>>> round(pair_orbit(PairState(e=0.5, kp=10, kv=20)).spectral_radius, 6)
0.523818
"""
from __future__ import annotations

import sys
import types

from hybridpd.explore.server import serve

__all__ = ["explore", "serve"]


def explore(**fields):
    """The explorer's page for the impact pair, to show in a notebook.

    Parameters
    ----------
    **fields
        Where the page starts: any field of :class:`~hybridpd.explore.state.PairState`
        (``case, e, mu, m2, gamma, omega, n, kp_min, kp_max, kv_min, kv_max, num, kp, kv,
        branch, stop, basin_num``), checked.

    Returns
    -------
    panel.layout.Row
        The page (display it, or ``.servable()``).

    Raises
    ------
    ValueError
        A field out of its range (named), or an unknown field.
    ImportError
        Panel or Bokeh is not installed (``pip install "hybridpd[explore]"``).

    Examples
    --------
    >>> import hybridpd as hp
    >>> page = hp.explore(e=0.1, kp=12.0)        # doctest: +SKIP
    """
    # deferred import: panel and the page load only when a page is built
    from hybridpd.explore.state import FIELDS, PairState

    unknown = sorted(set(fields) - set(FIELDS))
    if unknown:
        raise ValueError(f"explore takes the fields {', '.join(FIELDS)}; unknown: "
                         f"{', '.join(unknown)}")
    state = PairState(**fields)
    try:
        import panel as pn
    except ImportError as exc:
        raise ImportError("the explorer needs Panel and Bokeh: pip install "
                          "'hybridpd[explore]'") from exc
    # deferred import: panel and the page load only when a page is built
    from hybridpd.explore.app import PairExplorer

    if "ipykernel" in sys.modules:
        pn.extension()
    return PairExplorer(state, url=False).layout


class _ExplorePackage(types.ModuleType):
    """This package, callable as :func:`explore` (so ``hp.explore(...)`` works whichever of
    the package and the function Python binds to the name)."""

    def __call__(self, **fields):
        return explore(**fields)


sys.modules[__name__].__class__ = _ExplorePackage
