"""The available-surface inserter (3D) and its compiled geometry.

The 3D counterpart of :mod:`regopack.plugins.inserters.available_arc`: a new particle
``Q`` is placed touching an inserted particle ``P_k``, its centre drawn
uniformly by area on the part of the envelope boundary ``∂(P_k ⊕ (-Q))`` that
lies in the box of admissible centres and outside the open interior of every
interferer's envelope ``P_j ⊕ (-Q)``.

- :mod:`~regopack.plugins.inserters.available_surface.polyhedron`: the polyhedron
  representation and a builder from points (pure numpy and scipy);
- :mod:`~regopack.plugins.inserters.available_surface.polygon`: convex-polygon
  primitives in a plane (compiled);
- :mod:`~regopack.plugins.inserters.available_surface.envelope`: the envelope
  ``P ⊕ (-Q)`` (compiled);
- :mod:`~regopack.plugins.inserters.available_surface.free_surface`: the free part of
  an envelope's boundary and uniform sampling on it (compiled);
- :mod:`~regopack.plugins.inserters.available_surface.inserter`: the insertion loop and
  the plugin ``available-surface``.
"""
