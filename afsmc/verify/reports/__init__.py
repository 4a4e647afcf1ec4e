"""Many answers and their reports: sweeps (CSV, JSON, plots), parameter regions, JUnit."""
