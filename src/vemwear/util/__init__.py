"""Small helpers with no numerics: hashing of inputs (and, later, atomic files)."""
