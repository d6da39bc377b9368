"""Built-in scenes (TOML files), read with :func:`regopack.scene.load_scene`."""
