"""The plugin API: what a plugin file imports to declare an effect (docs/interface.md section 6).

``from gyrocal.effects import Effect, Parameter`` is the stable import for users' plugins; the
effect library itself lives in `gyrocal.model.effects`.
"""

from gyrocal.model.effects import Effect, Parameter

__all__ = ["Effect", "Parameter"]
