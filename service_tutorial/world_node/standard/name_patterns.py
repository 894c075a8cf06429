r"""
POSIX extended regular expressions on entity names, matched in time linear in the name.

The standard's name filter is a POSIX ERE. Python's `re` reads another dialect and backtracks:
'(a*)*b' takes seconds on a name of 24 letters. Here a pattern is parsed as ERE and run as a
Thompson automaton (all threads in step), so no pattern can hang the world. Supported: ordinary
characters, '.', bracket expressions with ranges, negation and the classes [:alpha:] and the
like, '^', '$', groups, '|', and the repetitions '*', '+', '?', '{m}', '{m,}' and '{m,n}'; a
backslash makes the next special character ordinary. Refused with a message: Python-only
syntax such as '(?', '\d' or lazy '*?', and patterns too long or too large to run.
A name matches when the pattern matches some part of it, as regexec does: anchor it with '^'
and '$' to match whole names.
"""

MAX_PATTERN_LENGTH = 256
MAX_REPEAT = 255  # POSIX's RE_DUP_MAX
MAX_PROGRAM = 2000  # instructions of the automaton, each visited at most once per character
_SPECIAL = set('.[]()*+?{}|^$\\')
_CLASSES = {
    'alpha': str.isalpha, 'digit': str.isdigit, 'alnum': str.isalnum, 'upper': str.isupper,
    'lower': str.islower, 'space': str.isspace, 'blank': lambda c: c in ' \t',
    'punct': lambda c: c.isprintable() and not c.isalnum() and not c.isspace(),
    'print': str.isprintable, 'graph': lambda c: c.isprintable() and not c.isspace(),
    'cntrl': lambda c: not c.isprintable(), 'xdigit': lambda c: c in '0123456789abcdefABCDEF',
}


class PatternError(ValueError):
    """A pattern that is not a POSIX ERE this matcher runs; the message says where and why."""


class NamePattern:
    """A compiled POSIX ERE: search(name) tells whether it matches a part of the name."""

    def __init__(self, pattern):
        """Compile pattern, or raise PatternError naming it."""
        if len(pattern) > MAX_PATTERN_LENGTH:
            raise PatternError(f'the pattern is {len(pattern)} characters long, more than '
                               f'{MAX_PATTERN_LENGTH}')
        parser = _Parser(pattern)
        tree = parser.alternatives()
        if parser.position < len(pattern):
            parser.fail("unmatched ')'")
        self._program = []
        _emit(tree, self._program)
        self._program.append(('match',))

    def search(self, name):
        """Return True if the pattern matches some part of name."""
        program, last = self._program, len(name)
        threads = []
        for index in range(last + 1):
            seen = set()
            for pc in threads:
                if _follow(program, pc, index, last, seen):
                    return True
            if _follow(program, 0, index, last, seen):
                return True
            if index == last:
                return False
            character = name[index]
            threads = [pc + 1 for pc in seen
                       if program[pc][0] == 'char' and program[pc][1](character)]
        return False


def _follow(program, pc, index, last, seen):
    """Add pc's epsilon closure at a position to seen; return True if it reaches the match."""
    stack = [pc]
    while stack:
        pc = stack.pop()
        if pc in seen:
            continue
        seen.add(pc)
        instruction = program[pc]
        kind = instruction[0]
        if kind == 'match':
            return True
        if kind == 'split':
            stack.extend((instruction[2], instruction[1]))
        elif kind == 'jump':
            stack.append(instruction[1])
        elif kind == 'start' and index == 0 or kind == 'end' and index == last:
            stack.append(pc + 1)
    return False


def _emit(node, program):
    """Append the instructions of a parsed node to program."""
    if len(program) > MAX_PROGRAM:
        raise PatternError(f'the pattern needs more than {MAX_PROGRAM} steps to run; '
                           'use fewer or smaller repetitions')
    kind = node[0]
    if kind in ('char', 'start', 'end'):
        program.append(node)
    elif kind == 'sequence':
        for part in node[1]:
            _emit(part, program)
    elif kind == 'either':
        jumps = []
        for branch in node[1][:-1]:
            split = len(program)
            program.append(None)
            _emit(branch, program)
            jumps.append(len(program))
            program.append(None)
            program[split] = ('split', split + 1, len(program))
        _emit(node[1][-1], program)
        for jump in jumps:
            program[jump] = ('jump', len(program))
    else:
        _emit_repeat(node, program)


def _emit_repeat(node, program):
    _, part, least, most = node
    for _ in range(least):
        _emit(part, program)
    if most is None:  # part*: a loop back through a split
        split = len(program)
        program.append(None)
        _emit(part, program)
        program.append(('jump', split))
        program[split] = ('split', split + 1, len(program))
        return
    splits = []
    for _ in range(most - least):  # each optional copy may be skipped to the end
        splits.append(len(program))
        program.append(None)
        _emit(part, program)
    for split in splits:
        program[split] = ('split', split + 1, len(program))


class _Parser:
    """Recursive descent over an ERE: alternatives of sequences of repeated atoms."""

    def __init__(self, pattern):
        self.pattern = pattern
        self.position = 0

    def fail(self, reason):
        raise PatternError(f'{reason} at position {self.position}')

    def peek(self):
        return self.pattern[self.position] if self.position < len(self.pattern) else ''

    def take(self):
        character = self.peek()
        self.position += 1
        return character

    def alternatives(self):
        branches = [self.sequence()]
        while self.peek() == '|':
            self.take()
            branches.append(self.sequence())
        return branches[0] if len(branches) == 1 else ('either', branches)

    def sequence(self):
        parts = []
        while self.peek() not in ('', '|', ')'):
            atom = self.atom()
            while self.peek() in ('*', '+', '?', '{'):
                atom = self.repetition(atom)
            parts.append(atom)
        return ('sequence', parts)

    def atom(self):
        character = self.take()
        if character in '*+?{':
            self.position -= 1
            self.fail(f"'{character}' repeats nothing")
        if character == '(':
            if self.peek() == '?':
                self.fail("'(?' is not POSIX ERE syntax")
            inner = self.alternatives()
            if self.take() != ')':
                self.fail("missing ')'")
            return inner
        if character == '.':
            return ('char', lambda _: True)
        if character == '^':
            return ('start',)
        if character == '$':
            return ('end',)
        if character == '[':
            return ('char', self.bracket())
        if character == '\\':
            escaped = self.take()
            if escaped not in _SPECIAL:
                self.position -= 1
                self.fail(f"'\\{escaped}' is not POSIX ERE syntax (a backslash may only make "
                          'a special character ordinary)')
            character = escaped
        return ('char', character.__eq__)

    def repetition(self, atom):
        character = self.take()
        if character == '*':
            least, most = 0, None
        elif character == '+':
            least, most = 1, None
        elif character == '?':
            least, most = 0, 1
        else:
            least, most = self.interval()
        if self.peek() == '?':
            self.fail("lazy repetition '?' is not POSIX ERE syntax")
        return ('repeat', atom, least, most)

    def interval(self):
        closing = self.pattern.find('}', self.position)
        text = self.pattern[self.position:closing] if closing >= 0 else ''
        low, comma, high = text.partition(',')
        if not low.isdigit() or (high and not high.isdigit()) or not text.isascii():
            self.fail("'{' must start an interval such as {2}, {2,} or {2,5}")
        least = int(low)
        most = least if not comma else (int(high) if high else None)
        if max(least, most or 0) > MAX_REPEAT or (most is not None and most < least):
            self.fail(f'interval {{{text}}} must have counts up to {MAX_REPEAT}, the first '
                      'not above the second')
        self.position = closing + 1
        return least, most

    def bracket(self):
        negated = self.peek() == '^'
        if negated:
            self.take()
        tests = []
        first = True
        while True:
            character = self.take()
            if character == '':
                self.fail("missing ']'")
            if character == ']' and not first:
                break
            first = False
            if character == '[' and self.peek() in ':.=':
                tests.append(self.bracket_class())
            elif self.peek() == '-' and self.pattern[self.position + 1:self.position + 2] \
                    not in ('', ']'):
                self.take()
                high = self.take()
                if high < character:
                    self.fail(f"range '{character}-{high}' runs backwards")
                tests.append(lambda c, low=character, high=high: low <= c <= high)
            else:
                tests.append(character.__eq__)
        if negated:
            return lambda c: not any(test(c) for test in tests)
        return lambda c: any(test(c) for test in tests)

    def bracket_class(self):
        kind = self.take()
        closing = self.pattern.find(kind + ']', self.position)
        if kind != ':' or closing < 0:
            self.fail("only character classes such as '[:alpha:]' are supported in brackets")
        name = self.pattern[self.position:closing]
        if name not in _CLASSES:
            self.fail(f"unknown character class '[:{name}:]'")
        self.position = closing + 2
        return _CLASSES[name]
