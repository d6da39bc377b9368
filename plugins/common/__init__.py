"""Compiled helpers that several kinds of plugin share.

Wall constraints, half-plane clipping, strips, atomics and borrowed arrays.
"""
