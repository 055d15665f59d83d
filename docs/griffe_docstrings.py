"""A griffe extension for the API pages: the package's reST markup read as markdown.

The docstrings use Sphinx roles (``:func:`solve```, ``:class:`~x.Y```) and ``::`` before
literal blocks; markdown has neither. A role becomes inline code (its last component when
written with ``~``) and a trailing ``::`` a single colon, so the pages read as written.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|data|attr|exc|obj|const)s?:`(~?)([^`]+)`")


def _role(match: re.Match[str]) -> str:
    tilde, target = match.groups()
    return f"`{target.rsplit('.', 1)[-1] if tilde else target}`"


def markdown_docstring(text: str) -> str:
    """``text`` with Sphinx roles as inline code and a line-ending ``::`` as ``:``."""
    text = _ROLE.sub(_role, text)
    return re.sub(r"(?<=\S)::[ \t]*$", ":", text, flags=re.M)


class ReSTRoles(griffe.Extension):
    """Rewrite every docstring as it is loaded (see the module docstring)."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown_docstring(obj.docstring.value)
