"""afsmc's own explorer: the lowered model's states as packed keys and each command's
choices vectorised per mode (`explore`, `explore_eval`), the clock's buckets explored in
order and assembled into the backward pass's arrays (`explore_graph`), and the keys found
and waiting with the branches' probability codes (`keysets`)."""
