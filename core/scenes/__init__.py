"""Scenes: the scene model and its checks, the JSON schema and the analyses a scene plans.

The built-in scenes are the TOML files here, read with
:func:`regopack.scenes.model.load_scene`.
"""
