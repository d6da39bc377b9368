"""The plugin contract and its registry.

Interfaces, spec records, hook specifications and the plugin manager.
"""
