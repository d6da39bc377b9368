"""Density controllers: the packing control coefficient eta."""
