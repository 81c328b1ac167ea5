"""Small helpers with no numerics: hashing of inputs, atomic files, what the machine
offers, and the allocator's reuse of freed memory."""
