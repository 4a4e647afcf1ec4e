"""The verification core: check and run drive the engines, bound each property over everything uncertain and build the answer."""
