"""The base layer: errors, messages, units, limits, files and threads that every other part uses.

Nothing here imports another part of regopack.
"""
