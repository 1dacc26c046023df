"""Sphinx configuration of sigmapi's documentation site.

Build (warnings are errors; the tests run the same build, tests/docs/test_docs.py):

    pip install -e '.[docs]'
    python -m sphinx -W --keep-going -b html docs docs/_build/html

Pages are MyST markdown; the tutorial (``tutorial.md``) is a MyST-NB text notebook executed
at build time; the gallery runs ``examples/*.py`` at their small size (``--small``); the
results pages render their tables from ``benchmarks/results/*.json`` (``_ext/sigmapi_results.py``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))

from sigmapi_extras import gallery_pattern, note_skipped, skipped_examples  # noqa: E402
from sigmapi_viewcode import fix_backlinks  # noqa: E402

import sigmapi  # noqa: E402

project = "sigmapi"
author = "the sigmapi authors"
copyright = "the sigmapi authors (MIT licence)"
release = sigmapi.__version__
version = release

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax served from the built site itself: no network at view time
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
    "sigmapi_results",
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb"}
root_doc = "index"
exclude_patterns = ["_build", "**.ipynb_checkpoints", "auto_examples/*.ipynb",
                    "auto_examples/*.py", "sg_execution_times.rst", "README.md",
                    "auto_examples/sg_execution_times.rst"]  # fmt: skip
templates_path = ["_templates"]
nitpicky = False

# -- MyST and the notebook ------------------------------------------------------------------
myst_enable_extensions = ["colon_fence", "dollarmath", "amsmath", "deflist", "attrs_inline"]
myst_heading_anchors = 3
nb_execution_mode = os.environ.get("SIGMAPI_DOCS_EXECUTE", "force")
nb_execution_timeout = 600
nb_execution_raise_on_error = True  # a failing cell fails the build
nb_execution_show_tb = True
nb_merge_streams = True


def _encrypt_the_kernel_transport() -> None:
    """Run the tutorial's kernel with its ZeroMQ sockets encrypted (CurveZMQ).

    MyST-NB starts the kernel through nbclient and jupyter_client, which connect to it over TCP
    on localhost, unencrypted unless the manager provisions Curve keys; ipykernel >= 7 then
    prints "Kernel is running over TCP without encryption" into every build. With
    ``transport_encryption = "auto"`` jupyter_client provisions the keys for a kernel whose
    kernelspec declares Curve support (ipykernel's ``python3`` does) and leaves any other kernel
    as before. MyST-NB passes no kernel manager settings through, so the trait's default is set
    here. (IPC sockets, the warning's other remedy, are files in the notebook's folder: a
    killed build leaves them behind, and the next build's kernel then does not answer.)"""
    try:
        import zmq
        from jupyter_client.manager import KernelManager
    except ImportError:  # without the docs extra there is no notebook to run
        return
    # an older jupyter_client without the option has no keys to make, nor does a libzmq built
    # without libsodium; the kernel then runs as before
    trait = KernelManager.class_traits().get("transport_encryption")
    if trait is not None and zmq.has("curve"):
        trait.default_value = "auto"


_encrypt_the_kernel_transport()

# -- API reference from the docstrings (numpydoc sections, read by napoleon) -----------------
autosummary_generate = True
autodoc_default_options = {"members": True, "inherited-members": True, "show-inheritance": False}
autodoc_member_order = "groupwise"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"
autodoc_preserve_defaults = True
autoclass_content = "class"
autodoc_inherit_docstrings = False  # Gymnasium's own docstrings are not numpydoc
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
napoleon_attr_annotations = True
napoleon_use_ivar = True  # the Attributes section as fields: no duplicate of a property
suppress_warnings = ["config.cache"]  # sphinx-gallery's reset_argv is a function

# -- the gallery: examples/*.py, run at their small size -------------------------------------
GALLERY_OUT = DOCS / "_build" / "gallery-figures"


def _reset_argv(gallery_conf, script_vars):
    """Command-line arguments of each example in the build: its small size, and a figure file
    for those that draw one (picked up by the scraper below)."""
    from sigmapi_results import gallery_argv

    return gallery_argv(Path(script_vars["src_file"]), GALLERY_OUT)


def _figure_scraper(block, block_vars, gallery_conf):
    from sigmapi_results import scrape_example_figure

    return scrape_example_figure(block_vars, gallery_conf, GALLERY_OUT)


# an example whose extra this environment lacks (compare_baselines.py: baselines, robot.py:
# robot) is shown, not run, and its page says so (_ext/sigmapi_extras.py)
SKIPPED = skipped_examples(ROOT / "examples", ROOT / "pyproject.toml")

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": gallery_pattern(SKIPPED),  # run every example, not only plot_*.py
    "reset_argv": _reset_argv,
    "image_scrapers": ("matplotlib", _figure_scraper),
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "plot_gallery": os.environ.get("SIGMAPI_DOCS_GALLERY", "True"),
    "capture_repr": (),
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "min_reported_time": 10**9,  # the times of a shared machine are no result
    "write_computation_times": False,  # its page loads scripts from the network
}

# -- HTML ------------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"sigmapi {release}"
html_static_path = ["_static"]
html_css_files = ["sigmapi.css"]
html_show_sourcelink = False


def _skip_member(app, what, name, obj, skip, options):
    """Skip what is documented elsewhere: names of the top-level namespace on a module page
    (they have their own page), and members a class inherits from outside sigmapi (tuple,
    Exception, gymnasium.Env)."""
    if skip:
        return None
    if what == "module" and name in sigmapi.__all__ and getattr(sigmapi, name, None) is obj:
        return True
    if what in ("class", "exception"):
        target = getattr(obj, "fget", obj)
        target = getattr(target, "__func__", target)
        if callable(target) or hasattr(obj, "__objclass__"):
            owner = getattr(target, "__module__", None)
            if owner is None:
                owner = getattr(getattr(target, "__objclass__", None), "__module__", None)
            if owner is not None and not str(owner).startswith("sigmapi"):
                return True
    return None


def setup(app):
    app.connect("autodoc-skip-member", _skip_member)
    app.connect("html-page-context", fix_backlinks)  # _ext/sigmapi_viewcode.py
    app.connect("source-read", lambda app, docname, source: note_skipped(SKIPPED, docname, source))
