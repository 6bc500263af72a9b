"""MkDocs hook: the site renders its equations offline.

MathJax 3 comes from the ``django-static-mathjax`` package of the docs extra (MathJax's own
files, no dependencies) and one component of it, SVG output with every TeX extension in one
file and no web fonts, is written into the built site beside ``javascripts/mathjax.js`` (its
configuration). :func:`on_config` fails the build when a page script or style sheet would come
from another host, so an offline build shows typeset equations, not raw TeX.
"""

from __future__ import annotations

from importlib.resources import files as package_files

from mkdocs.exceptions import PluginError
from mkdocs.structure.files import File, Files

#: The MathJax component inside the package, and where the site serves it (mkdocs.yml's
#: ``extra_javascript`` names that path).
COMPONENT = "static/mathjax/es5/tex-svg-full.js"
SITE_PATH = "javascripts/mathjax/tex-svg-full.js"


def on_config(config):
    """Refuse scripts and style sheets from another host (``extra_javascript``/``extra_css``)."""
    for key in ("extra_javascript", "extra_css"):
        remote = [str(entry) for entry in config[key] if "://" in str(entry)]
        if remote:
            raise PluginError(f"mkdocs.yml {key} loads {remote} from another host; serve it")
    return config


def on_files(files: Files, config) -> Files:
    """Add MathJax's component, read from the installed package, to the site's files."""
    try:
        source = package_files("mathjax").joinpath(COMPONENT)
    except ModuleNotFoundError:
        raise PluginError("the equations need MathJax: pip install 'stsf-gym[docs]'") from None
    if not source.is_file():
        raise PluginError(f"{source} is missing: reinstall django-static-mathjax")
    files.append(File.generated(config, SITE_PATH, abs_src_path=str(source)))
    return files
