"""Geometry that does not depend on the dimension's inserter: domains, particle batches, volumes."""
