// The VS Code client of afsmc's language server: starts `afsmc lsp` (stdio) for .afsm files.
"use strict";
const vscode = require("vscode");
const { LanguageClient } = require("vscode-languageclient/node");

let client;

function activate(context) {
  const [command, ...args] = vscode.workspace
    .getConfiguration("afsm")
    .get("server.command", ["afsmc", "lsp"]);
  client = new LanguageClient(
    "afsmc",
    "afsmc language server",
    { command, args },
    { documentSelector: [{ language: "afsm" }] }
  );
  context.subscriptions.push(client);
  return client.start().catch((err) => {
    vscode.window.showErrorMessage(
      `afsm: could not start '${command} ${args.join(" ")}' (${err.message}). ` +
        "Install afsmc or set afsm.server.command."
    );
  });
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
