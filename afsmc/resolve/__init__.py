"""Stage 2: the AST resolved into the typed IR (names bound, constants evaluated, types checked)."""
