"""One typed answer per property: the results, their verdicts, strategies and witnesses in mission terms."""
