"""The export pipeline: check a packing against an exporter and write its files."""
