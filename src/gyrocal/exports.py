"""A package's curated entry points, each imported from its module when first asked for (PEP 562).

A package's ``__init__`` names the few functions and classes a user starts from; importing the package
imports none of its modules, so a step that needs one module does not pay for the others' imports
(arviz, emcee, matplotlib: 1.5-2 s of CPU per job). ``from package import module`` works as before."""

import importlib
import sys

__all__ = ["lazy"]


def lazy(package: str, sources: dict) -> tuple:
    """``(__getattr__, __dir__)`` for ``package`` whose entry points ``sources`` maps to their module's
    name within it: each resolved from its module when first asked for."""

    def __getattr__(name):
        if name in sources:
            return getattr(importlib.import_module(f"{package}.{sources[name]}"), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(sources))

    return __getattr__, __dir__
