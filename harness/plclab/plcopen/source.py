"""Where things are in the ST text an XML project is made from.

The AST keeps start positions only, but a POU body must go into the XML exactly as it was
written (comments, layout, blank lines), and the comments that explain a POU or a
declaration are worth keeping as TC6 `documentation`. Both are cut from the text itself; a
scanner that knows comments and string literals is enough, because no keyword can hide
anywhere else.
"""
from __future__ import annotations

import bisect
import re
from dataclasses import dataclass
from typing import Any, Optional

from plclab.frontend import ast as A

_TOKEN = re.compile(r"""\(\*.*?\*\)|'(?:[^'$\n]|\$.)*'|"(?:[^"$\n]|\$.)*"|[A-Za-z_][A-Za-z0-9_]*|\S""", re.S)
_VAR_WORDS = {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_EXTERNAL", "VAR_GLOBAL", "VAR_TEMP"}


@dataclass(frozen=True)
class Token:
    kind: str    # 'comment' | 'string' | 'word' | 'other'
    text: str
    start: int
    end: int
    line: int

    @property
    def word(self) -> str:
        return self.text.upper() if self.kind == "word" else ""


class SourceText:
    """One checked ST text (the bundle) with the positions of its tokens."""

    def __init__(self, text: str):
        self.text = text
        self._line_starts = [0] + [m.end() for m in re.finditer(r"\n", text)]
        self.tokens: list[Token] = []
        for m in _TOKEN.finditer(text):
            t = m.group(0)
            kind = "comment" if t.startswith("(*") else "string" if t[0] in "'\"" else \
                "word" if t[0].isalpha() or t[0] == "_" else "other"
            self.tokens.append(Token(kind, t, m.start(), m.end(), self.line_of(m.start())))
        self._starts = [t.start for t in self.tokens]

    # -- positions -----------------------------------------------------------------------
    def line_of(self, offset: int) -> int:
        return bisect.bisect_right(self._line_starts, offset)

    def offset(self, node: A.Node | Any) -> int:
        """The text offset of a node's (1-based) line/column."""
        return self._line_starts[node.line - 1] + node.col - 1

    def index_at(self, offset: int) -> int:
        """The index of the token starting at `offset` (or the next one after it)."""
        return bisect.bisect_left(self._starts, offset)

    # -- POU bodies ------------------------------------------------------------------------
    def pou_body(self, pou: A.PouDecl) -> str:
        """The statement text of `pou`: from after its last END_VAR to its END_x, exactly as
        written except the line break after END_VAR and the whitespace before END_x."""
        first = self.offset(pou.body[0]) if pou.body else None
        i = self.index_at(self.offset(pou))
        start = None
        end_word = "END_" + pou.kind
        j = i + 1
        while j < len(self.tokens):
            tok = self.tokens[j]
            if first is not None and tok.start >= first:
                break
            if tok.word == "END_VAR":
                start = tok.end
            elif tok.word == end_word:
                break
            j += 1
        if start is None:   # no VAR block at all: the statements start the body
            start = first if first is not None else self.tokens[i].end
        k = self.index_at(start)
        while k < len(self.tokens) and self.tokens[k].word != end_word:
            k += 1
        end = self.tokens[k].start if k < len(self.tokens) else len(self.text)
        body = self.text[start:end]
        head, nl, rest = body.partition("\n")
        if nl and not head.strip():
            body = rest
        return body.rstrip()

    # -- comments ----------------------------------------------------------------------------
    def first_comment(self) -> Optional[str]:
        """The comment the text starts with (a bundle's title), if it does."""
        if self.tokens and self.tokens[0].kind == "comment":
            return _inner(self.tokens[0].text)
        return None

    def leading_comment(self, node: A.Node, skip_words: int = 0) -> Optional[str]:
        """The comments written right before `node` (or before the `skip_words` keywords that
        precede it, e.g. FUNCTION_BLOCK before the POU's name), none of them on the line of
        the code before them. The text's first comment (its title) is never included."""
        i = self.index_at(self.offset(node)) - skip_words
        comments: list[Token] = []
        j = i - 1
        while j >= 1 and self.tokens[j].kind == "comment":
            comments.append(self.tokens[j])
            j -= 1
        if j >= 0 and self.tokens[j].kind != "comment":
            code_line = self.tokens[j].line
            comments = [c for c in comments if c.line > code_line]
        if not comments:
            return None
        return "\n".join(_inner(c.text) for c in reversed(comments))

    def keyword_before(self, node: A.Node) -> str:
        """The word right before `node` (e.g. 'TYPE' before the first type declaration)."""
        i = self.index_at(self.offset(node)) - 1
        return self.tokens[i].word if i >= 0 else ""

    def line_comment(self, node: A.Node) -> Optional[str]:
        """The comment after the ';' that ends a one-line declaration, on the same line."""
        i = self.index_at(self.offset(node))
        seen_semicolon = False
        for tok in self.tokens[i:]:
            if tok.line != node.line:
                break
            if tok.text == ";":
                seen_semicolon = True
            elif tok.kind == "comment" and seen_semicolon:
                return _inner(tok.text)
        return None


def _inner(comment: str) -> str:
    return comment[2:-2].strip()
