"""The Octo assembler: Octo source text in, program bytes out (CHIP-8, SUPER-CHIP or XO-CHIP),
byte for byte as Octo builds it.

Octo (John Earnest's CHIP-8 language) is a one-pass, token-at-a-time assembler, and the bytes it
emits are part of its definition: `if vX > vY then` is three instructions through vF, a program
starts with a `jump main` unless `: main` comes first, forward references are patched when the
label arrives. This module follows Octo's own rules (the c-octo compiler's), including its
error cases, so a program that builds in Octo builds here to the same ROM; the difference is the
errors, which name the line, the column, what was expected and the valid choices.

The SCHIP and XO-CHIP statements are assembled too (hires, scroll-*, plane, `i := long`, ...):
the Timendus test-suite sources use them. The ROM is the bytes from 0x200 to the last one
written; addresses below 0x200 (`:org 0x100`) are assembled and dropped, as in Octo.
"""

from __future__ import annotations

import dataclasses
from typing import Optional

from octax_core.tools.octo import calc
from octax_core.tools.octo.errors import AssemblyError
from octax_core.tools.octo.tokens import Token, TokenStream, tokenize

PROGRAM_START = 0x200
MEMORY_SIZE = 0x10000
# Macros and string modes expand by splicing tokens back into the stream, so a macro that calls
# itself would expand forever, and N macros that each use the next twice expand to 2**N tokens.
# Octo has no limit; these stop both with an error, in a few seconds at most. Real programs nest
# a handful of levels and expand to tens of thousands of tokens (of the 116 Octo sources in
# ../shared, wdl.8o expands the most: 37,111).
MAX_EXPANSION_DEPTH = 256
MAX_EXPANDED_TOKENS = 500_000

RESERVED_WORDS = frozenset((
    ":=", "|=", "&=", "^=", "-=", "=-", "+=", ">>=", "<<=", "==", "!=", "<", ">", "<=", ">=",
    "key", "-key", "hex", "bighex", "random", "delay", ":", ":next", ":unpack", ":breakpoint",
    ":proto", ":alias", ":const", ":org", ";", "return", "clear", "bcd", "save", "load", "buzzer",
    "if", "then", "begin", "else", "end", "jump", "jump0", "native", "sprite", "loop", "while",
    "again", "scroll-down", "scroll-up", "scroll-right", "scroll-left", "lores", "hires",
    "loadflags", "saveflags", "i", "audio", "plane", ":macro", ":calc", ":byte", ":call",
    ":stringmode", ":assert", ":monitor", ":pointer", "pitch",
))

# vX <op> vY: the ALU instruction 8XYn.
REGISTER_OPS = {":=": 0x0, "|=": 0x1, "&=": 0x2, "^=": 0x3, "+=": 0x4, "-=": 0x5,
                ">>=": 0x6, "=-": 0x7, "<<=": 0xE}
# Statements of one fixed instruction.
FIXED_STATEMENTS = {";": 0x00EE, "return": 0x00EE, "clear": 0x00E0, "scroll-right": 0x00FB,
                    "scroll-left": 0x00FC, "exit": 0x00FD, "lores": 0x00FE, "hires": 0x00FF,
                    "audio": 0xF002}
# <word> vX: FXnn.
REGISTER_STATEMENTS = {"bcd": 0x33, "saveflags": 0x75, "loadflags": 0x85}
# <word> := vX: FXnn.
TIMER_STATEMENTS = {"delay": 0x15, "buzzer": 0x18, "pitch": 0x3A}
# Comparison pseudo-ops: (vF op, skip instruction) for `if vX <op> y then`; `vF := y` comes first.
PSEUDO_COMPARISONS = {">": (0x5, 0x4F), "<": (0x7, 0x4F), ">=": (0x7, 0x3F), "<=": (0x5, 0x3F)}
NEGATED = {"==": "!=", "!=": "==", "key": "-key", "-key": "key", ">": "<=", "<": ">=",
           ">=": "<", "<=": ">"}
CONDITION_OPERATORS = ("==", "!=", "key", "-key", "<", ">", "<=", ">=")
KEYPAD_CONSTANTS = {"1": 0x1, "2": 0x2, "3": 0x3, "4": 0xC, "Q": 0x4, "W": 0x5, "E": 0x6, "R": 0xD,
                    "A": 0x7, "S": 0x8, "D": 0x9, "F": 0xE, "Z": 0xA, "X": 0x0, "C": 0xB, "V": 0xF}


@dataclasses.dataclass(frozen=True)
class Program:
    """An assembled program: the ROM and the names the source gave.

    `labels` and `constants` map names to values (labels are addresses); `aliases` maps register
    names to indices (`:alias score v5` gives {"score": 5}), which is how a `GameSpec` can read
    a game's registers by the names its source uses.
    """

    rom: bytes
    labels: dict[str, int]
    constants: dict[str, float]
    aliases: dict[str, int]


@dataclasses.dataclass
class _Macro:
    args: list[str]
    body: list[Token]
    calls: int = 0


@dataclasses.dataclass
class _StringMode:
    values: dict[str, int] = dataclasses.field(default_factory=dict)  # char -> index in the alphabet
    bodies: dict[str, list[Token]] = dataclasses.field(default_factory=dict)
    calls: int = 0


@dataclasses.dataclass
class _ForwardReference:
    token: Token  # the first use, where an "undefined" error points
    uses: list[tuple[int, bool]]  # (address, is a 16-bit field)


@dataclasses.dataclass
class _Flow:
    address: int  # where the jump to patch is (-1: a loop's marker on the while stack)
    token: Optional[Token]
    kind: str


def assemble(source: str) -> bytes:
    """The CHIP-8 program that Octo `source` assembles to (loaded at 0x200).

    Raises:
        AssemblyError: the first error, with its line and column, what was expected and what
            was found; `str(error)` quotes the source line with a caret under the column.
    """
    return assemble_program(source).rom


def assemble_program(source: str) -> Program:
    """Like `assemble`, but also returns the labels, constants and register aliases."""
    if not isinstance(source, str):
        raise TypeError(f"assemble expects Octo source text (str), got {type(source).__name__}; "
                        "read a .8o file with Path(...).read_text()")
    return _Assembler(source).run()


class _Assembler:
    def __init__(self, source: str):
        self.stream = TokenStream(source, tokenize(source))
        self.rom = bytearray(MEMORY_SIZE)
        self.used = bytearray(MEMORY_SIZE)
        self.here = PROGRAM_START
        self.has_main = True
        self.constants: dict[str, float] = {f"OCTO_KEY_{k}": float(v) for k, v in KEYPAD_CONSTANTS.items()}
        self.labels: dict[str, int] = {}
        self.aliases: dict[str, int] = {"unpack-hi": 0, "unpack-lo": 1}
        self.mutable: set[str] = set()  # constants made by :calc, which :calc may redefine
        self.forward: dict[str, _ForwardReference] = {}
        self.macros: dict[str, _Macro] = {}
        self.string_modes: dict[str, _StringMode] = {}
        self.loops: list[_Flow] = []
        self.branches: list[_Flow] = []
        self.whiles: list[_Flow] = []
        self.expanded = 0  # tokens spliced in by macros and string modes so far

    # ---- driver ---------------------------------------------------------------------------

    def run(self) -> Program:
        self.emit(0x00, 0x00)  # the slot for `jump main`
        while not self.stream.at_end():
            self.statement()
        length = MEMORY_SIZE
        while length > PROGRAM_START and not self.used[length - 1]:
            length -= 1
        if self.has_main:
            if "main" not in self.labels:
                raise self.stream.error("this program has no 'main' label: execution starts at "
                                        "`: main`", at_end=True)
            self.patch_jump(PROGRAM_START, self.labels["main"])
        if self.forward:
            name, reference = next(iter(self.forward.items()))
            raise self.stream.error(f"undefined name '{name}': no label, constant or macro of "
                                    "that name is defined anywhere", reference.token)
        if self.loops:
            raise self.stream.error("this 'loop' has no matching 'again'", self.loops[-1].token)
        if self.branches:
            flow = self.branches[-1]
            raise self.stream.error(f"this '{flow.kind}' has no matching 'end'", flow.token)
        return Program(bytes(self.rom[PROGRAM_START:length]), dict(self.labels),
                       {k: v for k, v in self.constants.items() if k not in self.labels},
                       dict(self.aliases))

    # ---- emitting -------------------------------------------------------------------------

    def append(self, byte: int) -> None:
        if self.here > 0xFFFF:
            raise self.stream.error("ROM space is full: the program runs past address 0xFFFF")
        if self.here > PROGRAM_START and self.used[self.here]:
            raise self.stream.error(f"data overlap: address 0x{self.here:03X} has already been "
                                    "written (check the :org before this)")
        self.rom[self.here] = byte & 0xFF
        self.used[self.here] = 1
        self.here += 1

    def emit(self, high: int, low: int) -> None:
        self.append(high)
        self.append(low)

    def emit_word(self, word: int) -> None:
        self.emit(word >> 8, word & 0xFF)

    def immediate(self, opcode: int, nnn: int) -> None:
        self.emit(opcode | ((nnn >> 8) & 0xF), nnn & 0xFF)

    def patch_jump(self, address: int, destination: int) -> None:
        self.rom[address] = 0x10 | ((destination >> 8) & 0xF)
        self.rom[address + 1] = destination & 0xFF
        self.used[address] = self.used[address + 1] = 1

    # ---- reading names, registers and values ------------------------------------------------

    def register_index(self, name: str) -> Optional[int]:
        """The register a name stands for (v0-vF, either case, or an alias), else None."""
        if name in self.aliases:
            return self.aliases[name]
        if len(name) == 2 and name[0] in "vV" and name[1] in "0123456789abcdefABCDEF":
            return int(name[1], 16)
        return None

    def peek_is_register(self) -> bool:
        token = self.stream.peek()
        return token is not None and not token.is_number and self.register_index(token.value) is not None

    def register(self) -> int:
        token = self.stream.next("a register")
        index = None if token.is_number else self.register_index(token.value)
        if index is None:
            raise self.stream.error(f"expected a register (v0-vF or an alias), got {token.describe()}")
        return index

    def expect(self, word: str) -> None:
        token = self.stream.next(f"'{word}'")
        if token.value != word:
            raise self.stream.error(f"expected '{word}', got {token.describe()}")

    def name(self, kind: str) -> str:
        token = self.stream.next(f"a name for a {kind}")
        if token.is_number:
            raise self.stream.error(f"expected a name for a {kind}, got the number {token.describe()}")
        return self.check_name(token.value, kind)

    def check_name(self, name: str, kind: str) -> str:
        if name.startswith("OCTO_") or name in RESERVED_WORDS:
            article = "an" if kind[0] in "aeiou" else "a"
            raise self.stream.error(f"the name '{name}' is reserved and cannot be used for {article} {kind}")
        return name

    def string(self, what: str) -> Token:
        token = self.stream.next(what)
        if token.is_number:
            raise self.stream.error(f"expected {what}, got the number {token.describe()}")
        return token

    def constant(self, name: str) -> Optional[float]:
        return self.constants.get(name)

    def is_forward_reference(self, name: str) -> bool:
        return name in self.forward

    def rom_byte(self, address: int) -> int:
        return self.rom[address]

    def calculated(self, name: str) -> float:
        return calc.calculated(self.stream, self, name)

    def in_range(self, value: float, bits: int) -> int:
        number = int(value)
        low, high, text = {4: (0, 0xF, "4 bits: it must be in [0, 15]"),
                           8: (-128, 0xFF, "a byte: it must be in [-128, 255]"),
                           12: (0, 0xFFF, "12 bits: it must be in [0, 0xFFF]"),
                           16: (0, 0xFFFF, "16 bits: it must be in [0, 0xFFFF]")}[bits]
        if not low <= number <= high:
            raise self.stream.error(f"the value {number} does not fit in {text}")
        return number & high

    def known_value(self, token: Token, bits: int) -> Optional[int]:
        """A number or defined constant (labels above this line included), range-checked to
        `bits`; None for any other name, which each caller treats in its own way."""
        if token.is_number:
            return self.in_range(token.value, bits)
        value = self.constants.get(token.value)
        return None if value is None else self.in_range(value, bits)

    def value_fail(self, what: str, token: Token, undefined: bool) -> None:
        text = token.value
        if self.register_index(text) is not None:
            raise self.stream.error(f"expected {what} value, but found the register '{text}'")
        if text in RESERVED_WORDS:
            raise self.stream.error(f"expected {what} value, but found the keyword '{text}'; "
                                    "is a token missing before it?")
        if undefined:
            raise self.stream.error(f"expected {what} value, but '{text}' is not a defined constant "
                                    "(labels can be used here only after they are defined)")

    def small_value(self, bits: int) -> int:
        """A 4- or 8-bit operand: a number or a constant (never a forward reference)."""
        token = self.stream.next(f"{_article(bits)} {bits}-bit value")
        value = self.known_value(token, bits)
        if value is not None:
            return value
        self.value_fail(f"{_article(bits)} {bits}-bit", token, True)
        raise AssertionError("unreachable")

    def address_value(self) -> int:
        """A 12-bit operand: a number, a constant or label, or a label defined later."""
        token = self.stream.next("an address (a number or a label)")
        value = self.known_value(token, 12)
        if value is not None:
            return value
        self.value_fail("a 12-bit", token, False)
        self.refer_forward(token, self.here, is_long=False)
        return 0

    def long_value(self, forward_ok: bool, offset: int) -> int:
        """A 16-bit operand; forward references are patched at here + offset."""
        token = self.stream.next("a 16-bit value")
        value = self.known_value(token, 16)
        if value is not None:
            return value
        self.value_fail("a 16-bit", token, False)
        if not forward_ok:
            self.check_name(token.value, "label")
            raise self.stream.error(f"'{token.value}' must be defined before it is used here "
                                    "(a forward reference is not allowed)")
        self.refer_forward(token, self.here + offset, is_long=True)
        return 0

    def refer_forward(self, token: Token, address: int, is_long: bool) -> None:
        self.check_name(token.value, "label")
        reference = self.forward.setdefault(token.value, _ForwardReference(token, []))
        reference.uses.append((address, is_long))

    def constant_value(self) -> float:
        token = self.stream.next("a value for the constant")
        if token.is_number:
            return float(int(token.value))
        value = self.constants.get(token.value)
        if value is not None:
            return value
        if token.value in self.forward:
            raise self.stream.error(f"a constant may not refer to '{token.value}' before it is defined")
        self.value_fail("a constant", token, True)
        raise AssertionError("unreachable")

    # ---- statements -----------------------------------------------------------------------

    def statement(self) -> None:
        stream = self.stream
        if self.peek_is_register():
            self.register_statement(self.register())
            return
        token = stream.next()
        word = None if token.is_number else token.value
        handler = _STATEMENTS.get(word) if word is not None else None
        if handler is not None:
            handler(self, token)
        elif word in FIXED_STATEMENTS:
            self.emit_word(FIXED_STATEMENTS[word])
        elif word in REGISTER_STATEMENTS:
            self.emit(0xF0 | self.register(), REGISTER_STATEMENTS[word])
        elif word in TIMER_STATEMENTS:
            self.expect(":=")
            self.emit(0xF0 | self.register(), TIMER_STATEMENTS[word])
        elif token.is_number:
            number = int(token.value)
            if not -128 <= number <= 255:
                raise stream.error(f"the literal {number} does not fit in a byte: it must be in "
                                   "[-128, 255]")
            self.append(number)
        elif word in self.macros:
            self.expand_macro(word, token)
        elif word in self.string_modes:
            self.expand_string_mode(word, token)
        else:
            self.stream.splice([token])  # a bare name calls the subroutine of that label
            self.immediate(0x20, self.address_value())

    def register_statement(self, x: int) -> None:
        operator = self.stream.next("an operator after the register")
        op = None if operator.is_number else operator.value
        if op == ":=" and not self.peek_is_register():
            if self.stream.match("random"):
                self.emit(0xC0 | x, self.small_value(8))
            elif self.stream.match("key"):
                self.emit(0xF0 | x, 0x0A)
            elif self.stream.match("delay"):
                self.emit(0xF0 | x, 0x07)
            else:
                self.emit(0x60 | x, self.small_value(8))
        elif op == "+=" and not self.peek_is_register():
            self.emit(0x70 | x, self.small_value(8))
        elif op == "-=" and not self.peek_is_register():
            self.emit(0x70 | x, -self.small_value(8))
        elif op in REGISTER_OPS:
            self.emit(0x80 | x, (self.register() << 4) | REGISTER_OPS[op])
        else:
            raise self.stream.error(f"unknown operator {operator.describe()} after a register; "
                                    f"valid: {' '.join(REGISTER_OPS)}")

    def label(self, offset: int) -> None:
        target = self.here + offset
        name = self.name("label")
        if name in self.constants:
            raise self.stream.error(f"the name '{name}' has already been defined")
        if name in self.aliases:
            raise self.stream.error(f"the name '{name}' is already used by an alias")
        if target in (0x200, 0x202) and name == "main":
            self.has_main = False
            self.here = target = PROGRAM_START
            self.rom[0x200:0x202] = b"\0\0"
            self.used[0x200:0x202] = b"\0\0"
        self.constants[name] = float(target)
        self.labels[name] = target
        reference = self.forward.pop(name, None)
        if reference is None:
            return
        for address, is_long in reference.uses:
            if is_long and (self.rom[address] & 0xF0) == 0x60:  # :unpack long
                self.rom[address + 1] = (target >> 8) & 0xFF
                self.rom[address + 3] = target & 0xFF
            elif is_long:  # i := long, :pointer
                self.rom[address] = (target >> 8) & 0xFF
                self.rom[address + 1] = target & 0xFF
            elif target & 0xFFF != target:
                raise self.stream.error(f"the label '{name}' is at 0x{target:X}, which does not fit "
                                        "in the 12 bits of the instructions that use it")
            elif (self.rom[address] & 0xF0) == 0x60:  # :unpack
                self.rom[address + 1] = (self.rom[address + 1] & 0xF0) | ((target >> 8) & 0xF)
                self.rom[address + 3] = target & 0xFF
            else:
                self.rom[address] = (self.rom[address] & 0xF0) | ((target >> 8) & 0xF)
                self.rom[address + 1] = target & 0xFF

    def conditional(self, negated: bool) -> None:
        x = self.register()
        token = self.string("a comparison (" + " ".join(CONDITION_OPERATORS) + ")")
        op = NEGATED.get(token.value, token.value) if negated else token.value
        if op == "==":
            if self.peek_is_register():
                self.emit(0x90 | x, self.register() << 4)
            else:
                self.emit(0x40 | x, self.small_value(8))
        elif op == "!=":
            if self.peek_is_register():
                self.emit(0x50 | x, self.register() << 4)
            else:
                self.emit(0x30 | x, self.small_value(8))
        elif op == "key":
            self.emit(0xE0 | x, 0xA1)
        elif op == "-key":
            self.emit(0xE0 | x, 0x9E)
        elif op in PSEUDO_COMPARISONS:
            subtract, skip = PSEUDO_COMPARISONS[op]
            if self.peek_is_register():
                self.emit(0x8F, self.register() << 4)
            else:
                self.emit(0x6F, self.small_value(8))
            self.emit(0x8F, (x << 4) | subtract)
            self.emit(skip, 0x00)
        else:
            raise self.stream.error(f"expected a comparison, got {token.describe()}; valid: "
                                    + " ".join(CONDITION_OPERATORS))

    def expand_macro(self, name: str, call: Token) -> None:
        macro = self.macros[name]
        depth = self.expansion_depth(f"macro '{name}'", call)
        bindings: dict[str, Token] = {"CALLS": Token(float(macro.calls), call.line, call.column)}
        macro.calls += 1
        for arg in macro.args:
            if self.stream.at_end():
                raise self.stream.error(f"not enough arguments for macro '{name}': it takes "
                                        f"{len(macro.args)} ({' '.join(macro.args)})", call)
            bindings[arg] = self.stream.next()
        where = call.expansion or f"macro '{name}' called at line {call.line}"  # the source's call
        self.splice(self.instantiate(macro.body, bindings, where, depth), f"macro '{name}'", call)

    def expand_string_mode(self, name: str, call: Token) -> None:
        mode = self.string_modes[name]
        depth = self.expansion_depth(f"string mode '{name}'", call)
        text = self.string(f"a string for the string mode '{name}'")
        expansion = []
        for index, char in enumerate(text.value):
            if char not in mode.bodies:
                raise self.stream.error(f"string mode '{name}' is not defined for the character "
                                        f"{char!r}; defined: {''.join(mode.bodies)!r}", text,
                                        column_offset=index + text.quoted)
            bindings = {"CALLS": float(mode.calls), "CHAR": float(ord(char)), "INDEX": float(index),
                        "VALUE": float(mode.values[char])}
            mode.calls += 1
            expansion += self.instantiate(
                mode.bodies[char], {k: Token(v, call.line, call.column) for k, v in bindings.items()},
                call.expansion or f"string mode '{name}' used at line {call.line}", depth)
            if self.expanded + len(expansion) > MAX_EXPANDED_TOKENS:
                break  # `splice` reports it; a long string must not build a huge list first
        self.splice(expansion, f"string mode '{name}'", call)

    def expansion_depth(self, what: str, call: Token) -> int:
        """The depth of the tokens `call` expands to; an error past MAX_EXPANSION_DEPTH."""
        if call.depth >= MAX_EXPANSION_DEPTH:
            raise self.stream.error(
                f"{what} expands too deep: more than {MAX_EXPANSION_DEPTH} macro expansions nested "
                "inside each other. A macro that calls itself (directly, through another macro, or "
                "by rebuilding its own call from its arguments) never stops", call)
        return call.depth + 1

    def splice(self, tokens: list[Token], what: str, call: Token) -> None:
        """Puts an expansion in front of the stream, within the MAX_EXPANDED_TOKENS budget."""
        self.expanded += len(tokens)
        if self.expanded > MAX_EXPANDED_TOKENS:
            raise self.stream.error(
                f"macro expansion produced more than {MAX_EXPANDED_TOKENS:,} tokens (here in "
                f"{what}): macros that each use the next several times multiply, so this "
                "program would never finish assembling", call)
        self.stream.splice(tokens)

    @staticmethod
    def instantiate(body: list[Token], bindings: dict[str, Token], where: str, depth: int) -> list[Token]:
        """The body with its arguments bound. Every token, arguments included, is marked `depth`:
        an argument passed on is expanded again, and `dup dup` with `:macro dup X { X X }` must
        count as deeper each time it rebuilds itself."""
        out = []
        for token in body:
            bound = bindings.get(token.value) if not token.is_number else None
            chosen = bound or token
            out.append(Token(chosen.value, chosen.line, chosen.column, chosen.quoted,
                             chosen.expansion or where, depth))
        return out

    def block_body(self, what: str) -> list[Token]:
        opening = self.stream.next("'{'")
        if opening.value != "{":
            raise self.stream.error(f"expected '{{' to open the body of {what}, got {opening.describe()}")
        body, depth = [], 1
        while True:
            token = self.stream.peek()
            if token is None:
                raise self.stream.error(f"the body of {what} has no closing '}}'", at_end=True)
            if token.value == "{":
                depth += 1
            elif token.value == "}":
                depth -= 1
                if depth == 0:
                    self.stream.next()
                    return body
            body.append(self.stream.next())


def _article(bits: int) -> str:
    return "an" if bits == 8 else "a"


# ---- statements that start with a keyword ---------------------------------------------------

def _label(a: _Assembler, token: Token) -> None:
    a.label(0)


def _next_label(a: _Assembler, token: Token) -> None:
    a.label(1)


def _unpack(a: _Assembler, token: Token) -> None:
    if a.stream.match("long"):
        address = a.long_value(forward_ok=True, offset=0)
    else:
        nibble = a.small_value(4)
        address = (nibble << 12) | a.address_value()
    a.emit(0x60 | a.aliases["unpack-hi"], address >> 8)
    a.emit(0x60 | a.aliases["unpack-lo"], address)


def _skip_string(a: _Assembler, token: Token) -> None:
    a.string(f"a name after {token.value}")


def _monitor(a: _Assembler, token: Token) -> None:
    if a.peek_is_register():
        a.register()
        if a.stream.peek() is not None and a.stream.peek().is_number:
            a.small_value(4)
        else:
            a.string("a length or format string for the monitor")
    else:
        a.long_value(forward_ok=False, offset=0)
        if a.stream.peek() is not None and a.stream.peek().is_number:
            a.long_value(forward_ok=False, offset=0)
        else:
            a.string("a length or format string for the monitor")


def _assert(a: _Assembler, token: Token) -> None:
    message = None if a.stream.peek_is("{") else a.string("a message or '{'").value
    if not a.calculated("an assertion"):
        raise a.stream.error(f"assertion failed: {message}" if message else "assertion failed")


def _proto(a: _Assembler, token: Token) -> None:
    a.stream.next("a name after :proto")


def _alias(a: _Assembler, token: Token) -> None:
    name = a.name("alias")
    if name in a.constants:
        raise a.stream.error(f"the name '{name}' is already used by a constant")
    index = int(a.calculated("an alias")) if a.stream.peek_is("{") else a.register()
    if not 0 <= index <= 15:
        raise a.stream.error(f"a register index must be in [0, 15], got {index}")
    a.aliases[name] = index


def _byte(a: _Assembler, token: Token) -> None:
    if a.stream.peek_is("{"):
        a.append(int(a.calculated("a byte")) & 0xFF)
    else:
        a.append(a.small_value(8))


def _pointer(a: _Assembler, token: Token) -> None:
    if a.stream.peek_is("{"):
        address = int(a.calculated("a pointer"))
    else:
        address = a.long_value(forward_ok=True, offset=0)
    a.emit(address >> 8, address)


def _org(a: _Assembler, token: Token) -> None:
    if a.stream.peek_is("{"):
        a.here = 0xFFFF & int(a.calculated("an :org address"))
    else:
        a.here = a.long_value(forward_ok=False, offset=0)


def _call(a: _Assembler, token: Token) -> None:
    if a.stream.peek_is("{"):
        a.immediate(0x20, 0xFFF & int(a.calculated("a :call address")))
    else:
        a.immediate(0x20, a.address_value())


def _const(a: _Assembler, token: Token) -> None:
    name = a.name("constant")
    if name in a.constants:
        raise a.stream.error(f"the name '{name}' has already been defined")
    a.constants[name] = a.constant_value()


def _calc(a: _Assembler, token: Token) -> None:
    name = a.name("calculated constant")
    if name in a.constants and name not in a.mutable:
        raise a.stream.error(f"cannot redefine the name '{name}' with :calc (it was not made by :calc)")
    a.constants[name] = a.calculated(f"the constant '{name}'")
    a.mutable.add(name)


def _jump(opcode: int):
    def handler(a: _Assembler, token: Token) -> None:
        a.immediate(opcode, a.address_value())
    return handler


def _scroll(opcode: int):
    def handler(a: _Assembler, token: Token) -> None:
        a.emit(0x00, opcode | a.small_value(4))
    return handler


def _sprite(a: _Assembler, token: Token) -> None:
    x = a.register()
    y = a.register()
    a.emit(0xD0 | x, (y << 4) | a.small_value(4))


def _plane(a: _Assembler, token: Token) -> None:
    mask = a.small_value(4)
    if mask > 3:
        raise a.stream.error(f"the plane bitmask must be in [0, 3], got {mask}")
    a.emit(0xF0 | mask, 0x01)


def _memory(single: int, ranged: int):
    def handler(a: _Assembler, token: Token) -> None:
        x = a.register()
        if a.stream.match("-"):
            a.emit(0x50 | x, (a.register() << 4) | ranged)
        else:
            a.emit(0xF0 | x, single)
    return handler


def _index(a: _Assembler, token: Token) -> None:
    if a.stream.match(":="):
        if a.stream.match("long"):
            address = a.long_value(forward_ok=True, offset=2)
            a.emit(0xF0, 0x00)
            a.emit(address >> 8, address)
        elif a.stream.match("hex"):
            a.emit(0xF0 | a.register(), 0x29)
        elif a.stream.match("bighex"):
            a.emit(0xF0 | a.register(), 0x30)
        else:
            a.immediate(0xA0, a.address_value())
    elif a.stream.match("+="):
        a.emit(0xF0 | a.register(), 0x1E)
    else:
        found = a.stream.next("':=' or '+=' after i")
        raise a.stream.error(f"{found.describe()} is not an operator for the i register; "
                             "valid: := +=")


def _if(a: _Assembler, token: Token) -> None:
    ahead = 2 if (a.stream.peek_is("key", 1) or a.stream.peek_is("-key", 1)) else 3
    if a.stream.peek_is("then", ahead):
        a.conditional(negated=False)
        a.expect("then")
    elif a.stream.peek_is("begin", ahead):
        a.conditional(negated=True)
        a.expect("begin")
        a.branches.append(_Flow(a.here, token, "if ... begin"))
        a.emit(0x00, 0x00)
    else:
        found = a.stream.peek(ahead)
        raise a.stream.error("expected 'then' or 'begin' to finish the 'if', got "
                             + (found.describe() if found else "the end of the program"), found or token)


def _else(a: _Assembler, token: Token) -> None:
    if not a.branches:
        raise a.stream.error("this 'else' has no matching 'if ... begin'")
    flow = a.branches.pop()
    a.patch_jump(flow.address, a.here + 2)
    a.branches.append(_Flow(a.here, token, "else"))
    a.emit(0x00, 0x00)


def _end(a: _Assembler, token: Token) -> None:
    if not a.branches:
        raise a.stream.error("this 'end' has no matching 'if ... begin'")
    a.patch_jump(a.branches.pop().address, a.here)


def _loop(a: _Assembler, token: Token) -> None:
    a.loops.append(_Flow(a.here, token, "loop"))
    a.whiles.append(_Flow(-1, token, "loop"))


def _while(a: _Assembler, token: Token) -> None:
    if not a.loops:
        raise a.stream.error("this 'while' is not inside a 'loop ... again'")
    a.conditional(negated=True)
    a.whiles.append(_Flow(a.here, token, "while"))
    a.immediate(0x10, 0)


def _again(a: _Assembler, token: Token) -> None:
    if not a.loops:
        raise a.stream.error("this 'again' has no matching 'loop'")
    a.immediate(0x10, a.loops.pop().address)
    while True:
        flow = a.whiles.pop()
        if flow.address == -1:
            break
        a.patch_jump(flow.address, a.here)


def _macro(a: _Assembler, token: Token) -> None:
    name = a.name("macro")
    if name in a.macros:
        raise a.stream.error(f"the macro '{name}' has already been defined")
    args = []
    while not a.stream.at_end() and not a.stream.peek_is("{"):
        args.append(a.name("macro argument"))
    a.macros[name] = _Macro(args, [])  # defined before its body is read, as in Octo
    a.macros[name].body = a.block_body(f"the macro '{name}'")


def _string_mode(a: _Assembler, token: Token) -> None:
    name = a.name("string mode")
    mode = a.string_modes.setdefault(name, _StringMode())
    alphabet = a.string(f"the alphabet of the string mode '{name}'")
    body = a.block_body(f"the string mode '{name}'")
    for index, char in enumerate(alphabet.value):
        if char in mode.bodies:
            raise a.stream.error(f"string mode '{name}' is already defined for the character {char!r}",
                                 alphabet)
        mode.values[char] = index
        mode.bodies[char] = list(body)


_STATEMENTS = {
    ":": _label, ":next": _next_label, ":unpack": _unpack, ":breakpoint": _skip_string,
    ":monitor": _monitor, ":assert": _assert, ":proto": _proto, ":alias": _alias, ":byte": _byte,
    ":pointer": _pointer, ":org": _org, ":call": _call, ":const": _const, ":calc": _calc,
    "jump0": _jump(0xB0), "jump": _jump(0x10), "native": _jump(0x00),
    "scroll-down": _scroll(0xC0), "scroll-up": _scroll(0xD0), "sprite": _sprite, "plane": _plane,
    "save": _memory(0x55, 0x2), "load": _memory(0x65, 0x3), "i": _index, "if": _if, "else": _else,
    "end": _end, "loop": _loop, "while": _while, "again": _again, ":macro": _macro,
    ":stringmode": _string_mode,
}

__all__ = ["AssemblyError", "Program", "assemble", "assemble_program"]
