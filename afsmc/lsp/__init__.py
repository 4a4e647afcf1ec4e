"""The language server for .afsm files (`afsmc lsp`); see afsmc/lsp/server.py for its modules."""
