"""Instances on disk: parsing (JSON, GTSPLIB), reading and writing files, the bundled GTSPLIB
and the instance sets with their reference values."""
