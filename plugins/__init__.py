"""Built-in plugins of regopack.

Each module registers its spec records through the hooks of
:mod:`regopack.hookspecs`; the core lists them in
:data:`regopack.manager.BUILTIN_PLUGINS`.
"""
