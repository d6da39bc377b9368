"""regopack's benchmark suite for airspeed velocity (asv).

Run it from ``benchmarks/`` (where ``asv.conf.json`` is):

    asv run --python=same --quick      # a smoke run in the current environment
    asv run --python=same              # today's figures, this environment
    asv continuous main HEAD           # two commits, each built in its own environment

The modules use only the public API (``regopack.scene``, ``pack``, ``analyze``,
``export``, ``verify``, ``load``, ``save``); ``common`` holds the scenes and the
packings that several benchmarks share.
"""
