"""Public modules of a package that load on first use, not with the package.

Why: ``import web`` must not load the test viewer's websocket client, nor
``import vehicles`` more than the autopilot, just because a module is public.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from types import ModuleType

__all__ = ["lazy_modules"]


def lazy_modules(package: str, modules: tuple[str, ...]) -> Callable[[str], ModuleType]:
    """The module ``__getattr__`` of ``package``: ``package.<name>`` imports ``<name>`` of
    ``modules`` when first asked for; any other name is an AttributeError."""

    def load(name: str) -> ModuleType:
        if name in modules:
            return importlib.import_module(f"{package}.{name}")
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return load
