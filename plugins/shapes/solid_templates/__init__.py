"""Solid templates: convex hulls of STL meshes as the particles of 3D scenes.

- :mod:`~regopack.plugins.shapes.solid_templates.stl`: a strict STL reader (binary and ASCII);
- :mod:`~regopack.plugins.shapes.solid_templates.hull`: the hull with polygon faces, normalised;
- :mod:`~regopack.plugins.shapes.solid_templates.templates`: the files a path names, read once;
- :mod:`~regopack.plugins.shapes.solid_templates.shape`: the ``template-3d`` shape plugin.
"""
