#!/usr/bin/env python3
"""Prose statistics of a Markdown file: how long its sentences and table cells are.

Usage: python3 tools/prose_stats.py FILE.md [--show N]

Prints the file's lines, its words, its sentences, the average words per sentence, the five
longest sentences' lengths in words, and the longest table cell in characters. `--show N`
also prints the N longest sentences.

How the text is read:

- Fenced code blocks (``` or ~~~) are skipped whole: no words, no sentences.
- A table row (a line that starts with `|`) is split into cells at unescaped `|`. Each cell
  counts its words and its length in characters (stripped of the spaces around it), but no
  sentences. The separator row (`|---|`) is skipped.
- A heading (`#` to `######`) counts its words but is not a sentence.
- An image on its own line (`![alt](path)`) is skipped: alt text is a caption, not prose.
- The rest is prose. A blank line, a heading, a table row, a code fence and a list item's
  marker (`-`, `*`, `+` or `1.`) each end a block; indented lines continue the block above.
  A block's lines are joined with spaces.
- Links `[text](url)` count as their text. Inline code counts as the words in it, and a period
  inside it never ends a sentence.
- A block splits into sentences after `.`, `!` or `?` (possibly followed by a closing quote
  or bracket) when whitespace and then a capital letter, a digit, a backtick, a quote or an
  opening bracket follow. A few abbreviations never end a sentence: e.g., i.e., et al., etc.,
  vs., cf., Fig., Figs., Sec., Eq., No. The end of a block ends its last sentence, so a list
  item without a full stop is a sentence.
- A word is a whitespace-separated token with at least one letter or digit.
"""

import re
import sys

ABBREVIATIONS = ("e.g.", "i.e.", "al.", "etc.", "vs.", "cf.", "Fig.", "Figs.", "Sec.", "Eq.", "No.")
HEADING = re.compile(r"^#{1,6}\s")
LIST_ITEM = re.compile(r"^\s*([-*+]|\d+[.)])\s+")
IMAGE_LINE = re.compile(r"^\s*!\[[^\]]*\]\([^)]*\)\s*$")
LINK = re.compile(r"!?\[([^\]]*)\]\([^)]*\)")
CODE_SPAN = re.compile(r"`[^`]*`")
# The end of a sentence: punctuation, optional closers, whitespace, then what starts a sentence.
BOUNDARY = re.compile(r"([.!?][\"')\]]*)\s+(?=[A-Z0-9`\"'(\[])")
WORD = re.compile(r"\w")


def words(text):
    """The words of `text`: tokens with a letter or digit."""
    return [t for t in text.split() if WORD.search(t)]


def table_cells(line):
    """The cells of a table row, split at unescaped `|`, without the outer pipes."""
    body = line.strip()
    if body.startswith("|"):
        body = body[1:]
    if body.endswith("|") and not body.endswith("\\|"):
        body = body[:-1]
    return [c.strip() for c in re.split(r"(?<!\\)\|", body)]


MASK = {".": "\u2024", "?": "\u2047", "!": "\u2049"}


def mask_code(text):
    """`text` with periods, question and exclamation marks inside code spans made inert."""

    def inert(m):
        span = m.group(0)
        for mark, stand_in in MASK.items():
            span = span.replace(mark, stand_in)
        return span

    return CODE_SPAN.sub(inert, text)


def unmask(text):
    """`text` with the marks `mask_code` replaced put back."""
    for mark, stand_in in MASK.items():
        text = text.replace(stand_in, mark)
    return text


def sentences(block):
    """The sentences of one prose block."""
    text = mask_code(LINK.sub(r"\1", block))
    out, start = [], 0
    for m in BOUNDARY.finditer(text):
        end = m.end(1)
        before = text[start:end]
        last = before.split()[-1].lstrip("([\"'") if before.split() else ""
        if last in ABBREVIATIONS:
            continue
        out.append(unmask(text[start:end].strip()))
        start = m.end()
    rest = text[start:].strip()
    if rest:
        out.append(unmask(rest))
    return [s for s in out if words(s)]


def read(path):
    """Lines, prose blocks, heading texts and table cells of the Markdown file at `path`."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    blocks, headings, cells = [], [], []
    current = []
    fence = None

    def flush():
        if current:
            blocks.append(" ".join(current))
            current.clear()

    for line in lines:
        stripped = line.strip()
        if fence:
            if stripped.startswith(fence):
                fence = None
            continue
        if stripped.startswith("```") or stripped.startswith("~~~"):
            flush()
            fence = stripped[:3]
            continue
        if not stripped:
            flush()
            continue
        if HEADING.match(stripped):
            flush()
            headings.append(stripped.lstrip("#").strip())
            continue
        if stripped.startswith("|"):
            flush()
            row = table_cells(stripped)
            if all(re.fullmatch(r":?-{3,}:?", c) for c in row if c):
                continue
            cells.extend(row)
            continue
        if IMAGE_LINE.match(stripped):
            flush()
            continue
        item = LIST_ITEM.match(line)
        if item:
            flush()
            current.append(line[item.end():].strip())
            continue
        current.append(stripped)
    flush()
    return lines, blocks, headings, cells


def main(argv):
    args = list(argv[1:])
    show = 0
    if "--show" in args:
        i = args.index("--show")
        show = int(args[i + 1])
        del args[i : i + 2]
    if len(args) != 1:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    lines, blocks, headings, cells = read(args[0])
    found = [s for b in blocks for s in sentences(b)]
    lengths = sorted((len(words(s)) for s in found), reverse=True)
    prose_words = sum(len(words(b)) for b in blocks)
    heading_words = sum(len(words(h)) for h in headings)
    cell_words = sum(len(words(c)) for c in cells)
    longest_cell = max(cells, key=len, default="")
    print(f"file: {args[0]}")
    print(f"lines: {len(lines)}")
    print(
        f"words: {prose_words + heading_words + cell_words} "
        f"(prose {prose_words}, headings {heading_words}, table cells {cell_words})"
    )
    print(f"sentences: {len(found)}")
    average = sum(lengths) / len(lengths) if lengths else 0.0
    print(f"average words per sentence: {average:.1f}")
    print("longest sentences (words): " + ", ".join(str(n) for n in lengths[:5]))
    print(f"table cells: {len(cells)}, longest {len(longest_cell)} characters")
    if show:
        print()
        for s in sorted(found, key=lambda s: len(words(s)), reverse=True)[:show]:
            print(f"[{len(words(s))}] {s}")
        if longest_cell:
            print(f"\nlongest cell [{len(longest_cell)}]: {longest_cell}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
