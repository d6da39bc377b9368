"""Built-in plugins of regopack.

Each module registers its spec records through the hooks of
:mod:`regopack.registry.hookspecs`; the core lists them in
:data:`regopack.registry.manager.BUILTIN_PLUGINS`.
"""
