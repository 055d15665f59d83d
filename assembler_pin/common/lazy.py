"""Lazy package attributes: a name is imported from its home module on first access.

A package keeps a table ``{name: relative module}`` and gets its ``__getattr__`` and
``__dir__`` from :func:`lazy_attributes`, so that importing the package imports no numerical
library (the CLI's start-up) while every name stays one attribute access away.
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_attributes"]


def lazy_attributes(
    package: str, namespace: dict[str, Any], table: Mapping[str, str], submodules: bool = False
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` of ``package`` whose lazy names are ``table``.

    Args:
        package: the package's ``__name__``; namespace: its ``globals()`` (a name, once
            imported, is stored there and no longer looked up).
        table: name → the module it lives in, relative to the package (``".result"``).
        submodules: also give a subpackage or module of the package by its name
            (``ap.compliance``) when the name is not in ``table``.
    """

    def attribute(name: str) -> Any:
        module = table.get(name)
        if module is None:
            if submodules and importlib.util.find_spec(f"{package}.{name}") is not None:
                return importlib.import_module(f".{name}", package)
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        namespace[name] = value
        return value

    def names() -> list[str]:
        return sorted(set(namespace) | set(table))

    return attribute, names
