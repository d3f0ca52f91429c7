"""Sphinx configuration of the hybridpd documentation.

Build (warnings are errors)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

The API reference is generated from the docstrings (numpydoc format, autosummary): the flat
``hybridpd`` namespace from ``hybridpd.__all__`` (``api/namespace.rst`` is written here, at
every build), the subpackages recursively. The gallery runs every ``examples/<topic>/plot_*.py``
in quick mode (``-D plot_gallery=0`` skips running them).
"""
import shutil
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))          # the checkout being documented, before any install
sys.path.insert(0, str(DOCS / "_ext"))

import hybridpd_docs

import hybridpd

project = "hybridpd"
author = "hybridpd developers"
copyright = "hybridpd developers"
release = hybridpd.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

templates_path = ["_templates"]
exclude_patterns = ["_build", "**.ipynb_checkpoints", "auto_examples/**/*.ipynb"]
root_doc = "index"

# API reference ---------------------------------------------------------------------------
# Stub pages are regenerated at every build: a stale page of a name that moved would fail it.
shutil.rmtree(DOCS / "api" / "generated", ignore_errors=True)
N_NAMESPACE = hybridpd_docs.write_namespace_page(DOCS / "api" / "namespace.rst")
hybridpd_docs.fix_autosummary_summaries()
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"           # numpydoc's Parameters sections carry the types
add_module_names = False
numpydoc_show_class_members = False  # the class template documents the members itself
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# Gallery ---------------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "ignore_pattern": r"(^|[/\\])_\w*\.py$",  # the helper _out.py, not an example
    "subsection_order": [f"../examples/{t}"
                         for t in ("orbits", "regions", "design", "mechanical", "reproduction")],
    "within_subsection_order": "FileNameSortKey",
    "reset_argv": "hybridpd_docs.reset_argv",
    "image_scrapers": ("hybridpd_docs.scraper",),
    "abort_on_example_error": True,
    "download_all_examples": False,
    "remove_config_comments": True,
    "min_reported_time": 0,
    "show_memory": False,
}

# HTML ------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"hybridpd {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}
html_static_path = []


def _skip_gallery_images(app, config):
    # Without running the examples (-D plot_gallery=0) the guide's figures do not exist; that
    # quick build checks everything else, so their absence is not reported.
    if str(getattr(config, "plot_gallery", True)).lower() in ("0", "false"):
        config.suppress_warnings = [*config.suppress_warnings, "image.not_readable"]


def setup(app):
    app.connect("config-inited", _skip_gallery_images, priority=900)
    app.connect("build-finished", hybridpd_docs.check_gallery_figures)
