"""Insertion strategies, one package each.

Available-arc (2D), available-surface (3D) and random sequential addition (2D).
"""
