"""The assurance case of a mission (`afsmc report`, `Mission.report()`): what the mission
is, its requirements and their margins, what their verdicts hang on, how it fails, its
worst case, where its figures come from and how to reproduce it, all from one
verification (docs/report.md)."""
