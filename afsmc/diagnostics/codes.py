"""The registry of diagnostic codes: every code afsmc can report is declared here, once,
with its severity and a one-line title. Its explanation (prose, a wrong and a right
example) is afsmc/diagnostics/explanations/<CODE>.md; `afsmc explain CODE` prints it and
docs/diagnostics.md is generated from both (scripts/gen_diagnostics_doc.py).

Code that reports a diagnostic names its code from here (`codes.E301`). A `Code` is the
code's string ("E301"), so it compares, hashes and prints as the string does.

To add a code: declare it below in its range, write its explanation file, make a test
trigger it, and regenerate docs/diagnostics.md; tests/unit/diagnostics checks all four.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from afsmc.diagnostics.model import Severity

if TYPE_CHECKING:
    from afsmc.diagnostics.explain import Explanation


class Code(str):
    """A diagnostic code ("E301"), with its severity and one-line title."""

    severity: Severity
    # The title hides str.title(), which capitalises words: nothing capitalises a code.
    title: str  # type: ignore[assignment]

    def __new__(cls, code: str, severity: Severity, title: str) -> Code:
        prefix = {Severity.ERROR: "E", Severity.WARNING: "W", Severity.NOTE: "N"}[severity]
        if len(code) != 4 or code[0] != prefix or not code[1:].isdigit():
            raise ValueError(f"a {severity.value} code is {prefix} and three digits, not {code!r}")
        self = super().__new__(cls, code)
        self.severity = severity
        self.title = title
        return self

    @property
    def explanation(self) -> Explanation | None:
        """The explanation file's content, None if the code has none."""
        from afsmc.diagnostics.explain import load

        return load(str(self))

    def __repr__(self) -> str:
        return f"Code({str(self)!r}, {self.severity.value}, {self.title!r})"

    def __reduce__(self) -> tuple[object, ...]:  # pickles (to worker processes) as itself
        return (Code, (str(self), self.severity, self.title))


# E0xx: reading and writing files, afsmc's own failures

E001 = Code("E001", Severity.ERROR, "cannot read the input file")
E002 = Code("E002", Severity.ERROR, "refusing to overwrite the input")
E003 = Code("E003", Severity.ERROR, "cannot write an output")
E004 = Code("E004", Severity.ERROR, "the input is larger than afsmc reads")
E009 = Code("E009", Severity.ERROR, "internal error")


# E1xx: syntax

E101 = Code("E101", Severity.ERROR, "unexpected token")
E102 = Code("E102", Severity.ERROR, "missing ';' at the end of the declaration")
E103 = Code("E103", Severity.ERROR, "'=' is not a comparison")
E104 = Code("E104", Severity.ERROR, "a bounded integer is written [low..high]")
E105 = Code("E105", Severity.ERROR, "a variable's type is a range or bool, not a type name")
E106 = Code("E106", Severity.ERROR, "an outcome is written 'probability: updates;'")
E107 = Code("E107", Severity.ERROR, "updates of one outcome are separated by ','")
E108 = Code("E108", Severity.ERROR, "an action needs its modes")
E109 = Code("E109", Severity.ERROR, "an action's body is a block in braces")
E110 = Code("E110", Severity.ERROR, "a mode number must be a whole number")
E111 = Code("E111", Severity.ERROR, "a body mixes outcomes and plain updates")
E112 = Code("E112", Severity.ERROR, "missing '}'")
E113 = Code("E113", Severity.ERROR, "an expression nests more than 5000 levels deep")
E114 = Code("E114", Severity.ERROR, "an expression is nested too deeply for afsmc")
E115 = Code("E115", Severity.ERROR, "temporal operators do not nest")
E116 = Code("E116", Severity.ERROR, "missing ';' at the end of an outcome")
E117 = Code("E117", Severity.ERROR, "a comment or a label name is not closed")
E118 = Code("E118", Severity.ERROR, "a mode modifier is given twice")
E119 = Code("E119", Severity.ERROR, "an empty body")
E120 = Code("E120", Severity.ERROR, "the guard comes before the weight")
E121 = Code("E121", Severity.ERROR, "a step bound that is an expression is written in brackets")
E122 = Code("E122", Severity.ERROR, "a keyword is run into a name")
E123 = Code("E123", Severity.ERROR, "another language's spelling")
E124 = Code("E124", Severity.ERROR, "a hazard has one trigger")
E125 = Code("E125", Severity.ERROR, "a name, number or label name is longer than afsmc reads")
E190 = Code("E190", Severity.ERROR, "the formatter failed")


# E2xx: names and types

E201 = Code("E201", Severity.ERROR, "a name is declared twice")
E202 = Code("E202", Severity.ERROR, "a reserved name")
E203 = Code("E203", Severity.ERROR, "a name is not declared")
E204 = Code("E204", Severity.ERROR, "an interval constant must be an int or a prob")
E205 = Code("E205", Severity.ERROR, "an interval constant is empty")
E206 = Code("E206", Severity.ERROR, "an open constant has no value")
E207 = Code("E207", Severity.ERROR, "a prob constant is not in [0, 1]")
E208 = Code("E208", Severity.ERROR, "a --const value is not of the constant's type")
E209 = Code("E209", Severity.ERROR, "--const names no open constant")
E210 = Code("E210", Severity.ERROR, "a constant's value has the wrong type")
E211 = Code("E211", Severity.ERROR, "a constant cannot be evaluated")
E212 = Code("E212", Severity.ERROR, "a mode number is used twice")
E213 = Code("E213", Severity.ERROR, "no mode is marked initial")
E214 = Code("E214", Severity.ERROR, "more than one mode is marked initial")
E215 = Code("E215", Severity.ERROR, "not a mode")
E216 = Code("E216", Severity.ERROR, "an action or hazard acts in a final mode")
E217 = Code("E217", Severity.ERROR, "a tuple's initial value does not match its fields")
E218 = Code("E218", Severity.ERROR, "a bool variable cannot clamp")
E219 = Code("E219", Severity.ERROR, "a variable's range is empty")
E220 = Code("E220", Severity.ERROR, "an initial value is outside the variable's range")
E221 = Code("E221", Severity.ERROR, "a formula refers to itself")
E222 = Code("E222", Severity.ERROR, "an expression has the wrong type for where it stands")
E223 = Code("E223", Severity.ERROR, "no such field")
E224 = Code("E224", Severity.ERROR, "a constant cannot depend on the state")
E225 = Code("E225", Severity.ERROR, "a label is used outside a property")
E226 = Code("E226", Severity.ERROR, "operands of different types")
E227 = Code("E227", Severity.ERROR, "an action is not a value")
E228 = Code("E228", Severity.ERROR, "a constant is used before its declaration")
E229 = Code("E229", Severity.ERROR, "an interval constant is used outside updates")
E230 = Code("E230", Severity.ERROR, "a tuple is used as a value")
E231 = Code("E231", Severity.ERROR, "a constant cannot use a formula")
E232 = Code("E232", Severity.ERROR, "w(...) outside a weight")
E233 = Code("E233", Severity.ERROR, "unknown function")
E234 = Code("E234", Severity.ERROR, "wrong arguments to a function")
E235 = Code("E235", Severity.ERROR, "a probabilistic hazard has no weight")
E236 = Code("E236", Severity.ERROR, "a variable is assigned twice in one outcome")
E237 = Code("E237", Severity.ERROR, "an update does not fit its variable")
E238 = Code("E238", Severity.ERROR, "only variables can be assigned")
E239 = Code("E239", Severity.ERROR, "an update assigns a value of the wrong type")
E240 = Code("E240", Severity.ERROR, "weights refer to each other in a cycle")
E241 = Code("E241", Severity.ERROR, "a step bound must be an int >= 0")
E242 = Code("E242", Severity.ERROR, "a reward query must name its reward structure")
E244 = Code("E244", Severity.ERROR, "a property has the name of another's min or max query")
E245 = Code("E245", Severity.ERROR, "a number beyond a 64-bit integer or a finite double")
E246 = Code("E246", Severity.ERROR, "a formula nests too deeply once inlined")
E247 = Code("E247", Severity.ERROR, "an instantaneous reward of a structure without state rewards")
E248 = Code("E248", Severity.ERROR, "a probabilistic hazard is not an action")
E249 = Code("E249", Severity.ERROR, "a value beyond what Storm stores in a state")
E250 = Code("E250", Severity.ERROR, "an interval probability is used outside probabilities")
E251 = Code("E251", Severity.ERROR, "a threshold on a min or max query")
E252 = Code("E252", Severity.ERROR, "a threshold that is not a constant in range")
E253 = Code("E253", Severity.ERROR, "a composed mission that is not well formed")
E254 = Code("E254", Severity.ERROR, "an agent reads another agent's own variable")
E255 = Code("E255", Severity.ERROR, "an agent writes a shared variable it may not write")


# E3xx: the checks of a well-formed model

E301 = Code("E301", Severity.ERROR, "weights of enabled actions tie")
E302 = Code("E302", Severity.ERROR, "a weight lies outside [0, 1]")
E303 = Code("E303", Severity.ERROR, "an update can take a variable out of its range")
E304 = Code("E304", Severity.ERROR, "a probability lies outside [0, 1]")
E305 = Code("E305", Severity.ERROR, "outcome probabilities do not sum to 1")
E306 = Code("E306", Severity.ERROR, "an expression is undefined in some state")
E307 = Code("E307", Severity.ERROR, "an integer expression can leave 64 bits")
E308 = Code("E308", Severity.ERROR, "an int variable is assigned a pow with a negative exponent")
E310 = Code("E310", Severity.ERROR, "an expression nests deeper than Storm evaluates")
E311 = Code("E311", Severity.ERROR, "agents write the same variable in one step")
E312 = Code("E312", Severity.ERROR, "a synchronised action with no partner")
E313 = Code("E313", Severity.ERROR, "weights of an agent's enabled actions tie")
E314 = Code("E314", Severity.ERROR, "two agents' weights tie at the same time (ties weight)")


# W3xx: warnings of the checks

W301 = Code("W301", Severity.WARNING, "a non-final mode has no actions")
W302 = Code("W302", Severity.WARNING, "no action is enabled in some state of a mode")
W303 = Code("W303", Severity.WARNING, "a variable is never read")
W304 = Code("W304", Severity.WARNING, "a constant or formula is never used")
W305 = Code("W305", Severity.WARNING, "the mode numbers span too many values")
W306 = Code("W306", Severity.WARNING, "w(B) names an action that never acts in the weight's modes")
W307 = Code("W307", Severity.WARNING, "an interval probability makes a transition disappear at an end")
W308 = Code("W308", Severity.WARNING, "a property the parametric engine cannot bound over interval probabilities")
W309 = Code("W309", Severity.WARNING, "a check could not be completed")
W310 = Code("W310", Severity.WARNING, "a total reward of a structure that may be negative")


# E4xx: verification with Storm, and sweeps

W401 = Code("W401", Severity.WARNING, "a step-bounded G in JANI is asked as its dual")
E402 = Code("E402", Severity.ERROR, "a property Storm cannot check")
E403 = Code("E403", Severity.ERROR, "a model Storm cannot build")
E404 = Code("E404", Severity.ERROR, "a property the chosen Storm engine cannot check")
E405 = Code("E405", Severity.ERROR, "the model has more states than --max-states")
E406 = Code("E406", Severity.ERROR, "the Storm process ran out of memory or died")
E407 = Code("E407", Severity.ERROR, "no such property, or none declared")
E408 = Code("E408", Severity.ERROR, "the JANI backend is not available")
E409 = Code("E409", Severity.ERROR, "--formula holds more than one property")
E410 = Code("E410", Severity.ERROR, "nothing to sweep")
E411 = Code("E411", Severity.ERROR, "the generated model cannot be read by Storm")
N412 = Code("N412", Severity.NOTE, "the values that were answered before a failure")
E413 = Code("E413", Severity.ERROR, "the sweep's workers cannot be reached or started")
E414 = Code("E414", Severity.ERROR, "a process of the sweep died")
E440 = Code("E440", Severity.ERROR, "a parameter region makes the model ill-defined")
E441 = Code("E441", Severity.ERROR, "--param names no probability or param constant")
E442 = Code("E442", Severity.ERROR, "--require is not a bounded P or R property")
E443 = Code("E443", Severity.ERROR, "a property the parametric engine cannot check")
E415 = Code("E415", Severity.ERROR, "no strategy or failure path for this request")
E416 = Code("E416", Severity.ERROR, "a strategy needs the sparse engine, and the model does not fit")
E417 = Code("E417", Severity.ERROR, "a property cannot be split by cause")
E418 = Code("E418", Severity.ERROR, "the --baseline file cannot be used")
E419 = Code("E419", Severity.ERROR, "the --scratch directory cannot be used, or its disk is full")
E420 = Code("E420", Severity.ERROR, "a variable's range is too large for a build without a state limit")
N421 = Code("N421", Severity.NOTE, "--symmetry was not applied: something tells alike agents apart")


# E5xx: simulation and simulation-backed constants

E501 = Code("E501", Severity.ERROR, "unknown simulator output")
E502 = Code("E502", Severity.ERROR, "a constant has drifted from its simulation")
E503 = Code("E503", Severity.ERROR, "a simulator output does not fit its constant")
W503 = Code("W503", Severity.WARNING, "too few simulation runs to judge a constant")
E504 = Code("E504", Severity.ERROR, "a bad policy key of a simulation-backed constant")
E505 = Code("E505", Severity.ERROR, "a simulator failed")
E506 = Code("E506", Severity.ERROR, "the machine cannot be simulated")
E507 = Code("E507", Severity.ERROR, "the simulation's workers cannot be reached")
E508 = Code("E508", Severity.ERROR, "a constant has drifted and no value of its type fits")
E509 = Code("E509", Severity.ERROR, "the value sim-check --update would write does not check")
E510 = Code("E510", Severity.ERROR, "a constant's data file cannot be read")
E511 = Code("E511", Severity.ERROR, "a constant's data file has no such column")
E512 = Code("E512", Severity.ERROR, "a data column holds a cell that is not a number")
E513 = Code("E513", Severity.ERROR, "a data column holds no values")
E514 = Code("E514", Severity.ERROR, "a data column of outcomes holds a value other than 0 or 1")
E515 = Code("E515", Severity.ERROR, "a constant's data file lies outside the mission's folder")
E516 = Code("E516", Severity.ERROR, "a constant's data file is not a regular file")
E517 = Code("E517", Severity.ERROR, "a data file's rows do not match its header")


# E6xx: diagrams

E610 = Code("E610", Severity.ERROR, "the Graphviz program dot was not found")
E611 = Code("E611", Severity.ERROR, "the --results file cannot be used")
E612 = Code("E612", Severity.ERROR, "the reachability of the modes could not be computed")
E613 = Code("E613", Severity.ERROR, "the Graphviz program dot failed")


# W6xx: the mode graph

W601 = Code("W601", Severity.WARNING, "a mode is unreachable from the initial mode")
W602 = Code("W602", Severity.WARNING, "the mission cannot end once in a mode")
W603 = Code("W603", Severity.WARNING, "an action can never fire")


# E7xx: controllers for the robot, and conformance of the robot's logs

E701 = Code("E701", Severity.ERROR, "a composed mission has no controller")
E710 = Code("E710", Severity.ERROR, "a log file cannot be read")
E711 = Code("E711", Severity.ERROR, "a log line is not a step")
E712 = Code("E712", Severity.ERROR, "a logged step lacks a field or holds a bad value")
E713 = Code("E713", Severity.ERROR, "a logged step names what the spec does not declare")
E720 = Code("E720", Severity.ERROR, "a logged step the spec does not allow")
E721 = Code("E721", Severity.ERROR, "a constant has drifted from the logs")


# E9xx: the language server

E999 = Code("E999", Severity.ERROR, "the language server could not process the file")
N901 = Code("N901", Severity.NOTE, "the editor is shown the first 1,000 diagnostics of a file")


# The groups of docs/diagnostics.md and of `afsmc explain`: a heading and the prefixes
# ("E4": E400-E499) of the codes under it.
GROUPS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("E0xx: reading and writing files, afsmc's own failures", ("E0",)),
    ("E1xx: syntax", ("E1",)),
    ("E2xx: names and types", ("E2",)),
    ("E3xx: the checks of a well-formed model", ("E3",)),
    ("W3xx: warnings of the checks", ("W3",)),
    ("E4xx: verification with Storm, and sweeps", ("E4", "W4", "N4")),
    ("E5xx: simulation and simulation-backed constants", ("E5", "W5")),
    ("E6xx: diagrams", ("E6",)),
    ("W6xx: the mode graph", ("W6",)),
    ("E7xx: controllers for the robot, and conformance of the robot's logs", ("E7",)),
    ("E9xx: the language server", ("E9", "N9")),
)

REGISTRY: dict[str, Code] = {str(c): c for c in list(globals().values()) if isinstance(c, Code)}


def lookup(code: str) -> Code | None:
    """The registry's code named `code` (any case), None if there is none."""
    return REGISTRY.get(code.strip().upper())


def group_of(code: str) -> str:
    """The heading of the group that holds `code`."""
    return next(head for head, prefixes in GROUPS if code[:2] in prefixes)
