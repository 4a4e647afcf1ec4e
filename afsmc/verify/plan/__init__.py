"""What to ask: the queries of each property (duals, complements), the precision and exact modes, the refusal of a counter too deep for a symbolic build."""
