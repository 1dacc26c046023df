"""The ``[docs]`` back-links of the highlighted source pages (``_modules/``) point at the
definition that documents each object.

``sphinx.ext.viewcode`` keeps one prefix per module for every back-link of its source page:
the module name under which the *first* object of that module was documented. An object of
``sigmapi.metrics`` that the API page documents under the top-level name (``sigmapi.evaluate``)
sets it to ``sigmapi``, and then the back-link of a function documented only on the module's
own page (``sigmapi.metrics.affine_fit``) points at ``#sigmapi.affine_fit``, an anchor no page
has. :func:`fix_backlinks` (``html-page-context``) points each back-link whose anchor is no
documented object at the module's own name for it, when that one is documented on the linked
page.
"""

from __future__ import annotations

import posixpath
import re
from typing import Any

__all__ = ["fix_backlinks"]

BACKLINK = re.compile(
    r'(<div class="viewcode-block" id="(?P<name>[^"]+)">\s*<a class="viewcode-back" '
    r'href="(?P<url>[^"#]*)#)(?P<anchor>[^"]+)"'
)


def fix_backlinks(app: Any, pagename: str, templatename: str, context: dict, doctree: Any) -> None:
    """Rewrite the back-links of one ``_modules/`` page (an ``html-page-context`` handler)."""
    if not pagename.startswith("_modules/") or "body" not in context:
        return
    module = pagename.removeprefix("_modules/").replace("/", ".")
    objects = app.env.get_domain("py").objects  # full name -> (docname, node_id, ...)
    here = posixpath.dirname(pagename)

    def docname_of(url: str) -> str:
        return posixpath.normpath(posixpath.join(here, url)).removesuffix(".html")

    def fix(m: re.Match[str]) -> str:
        target, anchor = docname_of(m["url"]), m["anchor"]
        if anchor in objects and objects[anchor].docname == target:
            return m.group(0)
        own = f"{module}.{m['name']}"
        if own in objects and objects[own].docname == target:
            return f'{m.group(1)}{objects[own].node_id}"'
        return m.group(0)

    context["body"] = BACKLINK.sub(fix, context["body"])
