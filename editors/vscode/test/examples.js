// Tokenizes every example (../../examples/*.afsm) with the grammar and fails if any
// character outside whitespace is left unscoped or marked invalid, or if a declaration
// keyword at the start of a line is not highlighted as one.
"use strict";
const fs = require("fs");
const path = require("path");
const vsctm = require("vscode-textmate");
const oniguruma = require("vscode-oniguruma");

const wasm = fs.readFileSync(require.resolve("vscode-oniguruma/release/onig.wasm")).buffer;
const onigLib = oniguruma.loadWASM(wasm).then(() => ({
  createOnigScanner: (patterns) => new oniguruma.OnigScanner(patterns),
  createOnigString: (s) => new oniguruma.OnigString(s),
}));
const registry = new vsctm.Registry({
  onigLib,
  loadGrammar: async () =>
    vsctm.parseRawGrammar(
      fs.readFileSync(path.join(__dirname, "..", "syntaxes", "afsm.tmLanguage.json"), "utf8"),
      "afsm.tmLanguage.json"
    ),
});

const DECL = /^(machine|const|param|var|mode|action|hazard|formula|label|rewards|property)\b/;

(async () => {
  const grammar = await registry.loadGrammar("source.afsm");
  const dir = path.join(__dirname, "..", "..", "..", "examples");
  const files = fs.readdirSync(dir).filter((f) => f.endsWith(".afsm")).sort();
  if (files.length === 0) throw new Error(`no examples in ${dir}`);
  let problems = 0;
  for (const file of files) {
    const lines = fs.readFileSync(path.join(dir, file), "utf8").split("\n");
    let state = vsctm.INITIAL;
    lines.forEach((line, i) => {
      const res = grammar.tokenizeLine(line, state);
      state = res.ruleStack;
      for (const tok of res.tokens) {
        const text = line.slice(tok.startIndex, tok.endIndex);
        const bare = tok.scopes.length === 1 && text.trim() !== "";
        const invalid = tok.scopes.some((s) => s.startsWith("invalid"));
        if (bare || invalid) {
          problems++;
          console.error(`${file}:${i + 1}:${tok.startIndex + 1}: '${text}' ${tok.scopes.join(" ")}`);
        }
      }
      const m = DECL.exec(line);
      if (m && res.tokens.length) {
        const first = res.tokens[0].scopes;
        if (!first.includes("keyword.declaration.afsm")) {
          problems++;
          console.error(`${file}:${i + 1}: '${m[1]}' is not a declaration keyword: ${first.join(" ")}`);
        }
      }
    });
  }
  if (problems) {
    console.error(`${problems} problem(s)`);
    process.exit(1);
  }
  console.log(`examples: ${files.length} file(s) highlighted without unscoped or invalid text`);
})().catch((err) => {
  console.error(err);
  process.exit(1);
});
