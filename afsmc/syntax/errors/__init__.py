"""Diagnosing a syntax error: where lark stopped, turned into a diagnostic for people.

- messages: wording shared with the resolver, and names of the grammar's terminals;
- examples: common mistakes, recognised by the parser state their examples fail in;
- hints: spellings from other languages (Python, PRISM) and the hints that fix them;
- diagnose: report_syntax_error, which tries each explanation in turn.
"""
