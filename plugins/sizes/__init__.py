"""Size-distribution plugins: the Chang'e-5 distribution and the generic ones."""
