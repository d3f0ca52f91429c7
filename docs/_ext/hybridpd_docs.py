"""Build helpers of the documentation: the namespace page and the gallery's runner hooks.

* :func:`write_namespace_page` writes ``api/namespace.rst`` from ``hybridpd.__all__`` when
  the build starts, so that the reference of the flat ``hybridpd`` namespace lists exactly
  the names the package exports, whatever they are at that commit.
* :func:`reset_argv` runs every example of the gallery as ``plot_x.py --quick --out DIR``
  with a fresh ``DIR`` under the build directory (the examples save their figures with
  :meth:`matplotlib.figure.Figure.savefig`, without pyplot).
* :func:`scraper` puts the image files an example wrote into ``DIR`` on its page, in the
  order of their paths, so the gallery shows exactly what a user running the script gets.

Sphinx-gallery takes the two hooks by their qualified names (``hybridpd_docs.reset_argv``),
which keeps the configuration picklable.
"""
from __future__ import annotations

import inspect
import shutil
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
GALLERY_OUT = DOCS / "_build" / "gallery-out"
IMAGE_SUFFIXES = (".png", ".svg", ".jpg")


def _kind(obj) -> str:
    if inspect.isclass(obj):
        return "exception" if issubclass(obj, BaseException) else "class"
    if inspect.ismodule(obj):
        return "module"
    if callable(obj):
        return "function"
    return "data"


def namespace_names():
    """``(kind, name)`` of every public name in ``hybridpd.__all__``, sorted by kind and name."""
    import hybridpd

    out = []
    for name in sorted(set(hybridpd.__all__)):
        if name.startswith("_"):
            continue  # __version__ and friends are not API pages
        out.append((_kind(getattr(hybridpd, name)), name))
    order = {"class": 0, "function": 1, "exception": 2, "module": 3, "data": 4}
    return sorted(out, key=lambda kn: (order[kn[0]], kn[1].lower()))


_TITLES = {"class": "Classes", "function": "Functions", "exception": "Exceptions",
           "module": "Modules", "data": "Constants"}


def write_namespace_page(path: Path) -> int:
    """Write the autosummary page of the flat namespace to ``path``; the number of names."""
    names = namespace_names()
    lines = [
        ".. This file is generated from hybridpd.__all__ when the documentation is built.",
        "",
        "The ``hybridpd`` namespace",
        "==========================",
        "",
        "Everything a script needs is importable from the package itself",
        "(``import hybridpd as hp``; ``hp.symmetric_orbit(...)``): this page lists",
        "``hybridpd.__all__``. Each name is also documented where it is defined, in the",
        ":doc:`subpackage reference <index>`.",
        "",
        ".. currentmodule:: hybridpd",
        "",
    ]
    for kind in ("class", "function", "exception", "module", "data"):
        group = [n for k, n in names if k == kind]
        if not group:
            continue
        title = _TITLES[kind]
        lines += [title, "-" * len(title), "", ".. autosummary::"]
        if kind != "data":
            lines.append("   :toctree: generated/")
        lines += ["   :nosignatures:", ""] + [f"   {n}" for n in group] + [""]
    text = "\n".join(lines)
    if not path.exists() or path.read_text() != text:  # unchanged: no rebuild of the page
        path.write_text(text)
    return len(names)


def _out_dir(src_file) -> Path:
    src = Path(src_file)
    return GALLERY_OUT / src.parent.name / src.stem


def reset_argv(gallery_conf, script_vars):
    """Arguments of an example in the gallery: quick mode, figures into a fresh folder."""
    out = _out_dir(script_vars["src_file"])
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    return ["--quick", "--out", str(out)]


def scraper(block, block_vars, gallery_conf):
    """Images the example has written into its ``--out`` folder since the last block."""
    from sphinx_gallery.scrapers import figure_rst

    out = _out_dir(block_vars["src_file"])
    seen = block_vars.setdefault("hybridpd_scraped", set())
    new = sorted(p for p in out.rglob("*") if p.suffix in IMAGE_SUFFIXES and p not in seen)
    paths = []
    for src, dst in zip(new, block_vars["image_path_iterator"]):
        dst = Path(dst).with_suffix(src.suffix)
        shutil.copyfile(src, dst)
        seen.add(src)
        paths.append(str(dst))
    return figure_rst(paths, gallery_conf["src_dir"])


def check_gallery_figures(app, exception):
    """Warn (an error under ``-W``) for every example whose gallery page shows no figure."""
    if exception is not None or str(app.config.plot_gallery).lower() in ("0", "false"):
        return
    from sphinx.util import logging

    logger = logging.getLogger(__name__)
    gallery = Path(app.srcdir) / "auto_examples"
    for script in sorted((DOCS.parent / "examples").glob("*/plot_*.py")):
        images = gallery / script.parent.name / "images"
        if not list(images.glob(f"sphx_glr_{script.stem}_001.*")):
            logger.warning(f"gallery: {script.parent.name}/{script.name} shows no figure "
                           f"(it must save at least one image into its --out folder)")


def fix_autosummary_summaries():
    """Make autosummary's one-line summaries end outside inline literals.

    Autosummary cuts a docstring's first sentence at the first ``". "``; it means to extend
    the cut while the cut text has broken markup, but checks the whole paragraph instead, so
    a period inside a literal (``w . q``, ``z . (A z + q)``) cuts the summary in the middle
    of the literal (a docutils warning, an error under ``-W``). The cut is extended here to
    the first sentence end after which every literal is closed.
    """
    import re

    from sphinx.ext import autosummary

    original = autosummary.extract_summary
    if getattr(original, "_hybridpd_fixed", False):
        return

    def extract_summary(doc, settings):
        summary = original(doc, settings)
        if summary.count("``") % 2 == 0:
            return summary
        stanza = []
        for line in doc:
            if line.strip():
                stanza.append(line.strip())
            elif stanza:
                break
        text = " ".join(stanza)
        sentences = re.split(r"\.\s+", text)
        for i in range(len(sentences)):
            candidate = ". ".join(sentences[: i + 1]).rstrip(".") + "."
            if candidate.count("``") % 2 == 0:
                return candidate
        return text

    extract_summary._hybridpd_fixed = True
    autosummary.extract_summary = extract_summary
