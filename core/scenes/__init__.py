"""Built-in scenes (TOML files), read with :func:`regopack.scene_model.load_scene`."""
