"""Object models: outlines checked and oriented, object files, 3-D meshes sliced on a table,
the prior (DESIGN §4.1, §4.13, §4.14, §8)."""
