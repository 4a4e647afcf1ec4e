"""A model as flat arrays and its exact backward pass: `umb.py` reads Storm's sparse model
through its binary export, afsmc's explorer (afsmc.verify.explorer) assembles the same
arrays from its own exploration, and `acyclic.py` answers every P [F] and R [F] query of a
model acyclic but for self-loops by one backward pass over them."""
