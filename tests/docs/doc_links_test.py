#!/usr/bin/env python3
"""The user's documents hold together: in README.md, docs/*.md and the repository's other Markdown
files every relative link names a file or directory of the repository, every #anchor a heading of its document (GitHub's anchors), and
every section named in words (`docs/results.md, "Training"`, `README, "One flight"`, `section
"Scan"`) a heading of that document; README.md stays a guide of at most 250 lines whose test
command is what CI runs.
Usage: doc_links_test.py SOURCE_DIR
"""
import os
import re
import sys
import unittest

SOURCE = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", ".."))
README_MAX_LINES = 250

LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
# A document and a quoted section: `README, "One flight"`, `docs/results.md, "Training"`,
# `[docs/design.md](docs/design.md), "Time: two clocks"`, `EMULATION.md "Scan"`.
# The quote may wrap onto the next line.
NAMED = re.compile(r"(?<![\w/.-])((?:[\w.-]+/)*[\w.-]+\.md|README)\)?,?\s\"([^\"]{1,150})\"")
# The document's own sections: `section "Scan"`, `(section "Tilt first, ..." at the end)`.
OWN = re.compile(r"\b[Ss]ection\s\"([^\"]{1,150})\"")


def prose(text):
    """The document without fenced code blocks and code spans, line numbers kept."""
    out, fenced = [], False
    for line in text.split("\n"):
        if re.match(r"\s*(```|~~~)", line):
            fenced = not fenced
            out.append("")
            continue
        out.append("" if fenced else re.sub(r"`+[^`]*`+", "``", line))
    return out


def headings(path):
    """A document's headings: their texts and GitHub's anchors of them."""
    texts, anchors, seen = [], set(), {}
    with open(path, encoding="utf-8") as f:
        fenced = False
        for line in f:
            if re.match(r"\s*(```|~~~)", line):
                fenced = not fenced
            if fenced:
                continue
            m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
            if not m:
                continue
            text = m.group(1)
            texts.append(text)
            plain = re.sub(r"[`*_]|\[([^\]]*)\]\([^)]*\)", r"\1", text).strip().lower()
            slug = re.sub(r"[^\w\- ]", "", plain).replace(" ", "-")
            n = seen.get(slug, 0)
            seen[slug] = n + 1
            anchors.add(slug if n == 0 else "%s-%d" % (slug, n))
    return texts, anchors


def names_heading(texts, section):
    """A section named in words is a heading that reads the same, or begins so (a heading may go
    on with a date or a subtitle: "Training" names "Training (2026-12-04)"; a numbered heading is
    named without its number: "Topics" names "3. Topics")."""
    want = re.sub(r"[`*]", "", section).strip().lower()
    for t in texts:
        have = re.sub(r"[`*]", "", t).strip().lower()
        if not want[:1].isdigit():
            have = re.sub(r"^\d+(\.\d+)*\.?\s+", "", have)
        if have == want or (have.startswith(want) and not have[len(want)].isalnum()):
            return True
    return False


def documents():
    """README.md, docs/*.md and every other Markdown file of the repository (not build trees)."""
    found = []
    for root, dirs, files in os.walk(SOURCE):
        dirs[:] = sorted(d for d in dirs if not d.startswith((".", "build")))
        found += [os.path.join(root, f) for f in sorted(files) if f.endswith(".md")]
    return found


def find_document(name, base):
    """A document named in words: beside the one naming it, at the root, in docs/, or the only
    file of that name in the repository."""
    if name == "README":
        name = "README.md"
    for d in (base, SOURCE, os.path.join(SOURCE, "docs")):
        p = os.path.normpath(os.path.join(d, name))
        if os.path.isfile(p):
            return p
    found = []
    for root, dirs, files in os.walk(SOURCE):
        dirs[:] = [d for d in dirs if not d.startswith((".", "build"))]
        if os.path.basename(name) in files and os.path.join(root, os.path.basename(name)).endswith(name):
            found.append(os.path.join(root, os.path.basename(name)))
    return found[0] if len(found) == 1 else None


def problems(path):
    """Every broken link and section reference of one document, as 'FILE:LINE: what'."""
    rel = os.path.relpath(path, SOURCE)
    base = os.path.dirname(path)
    out = []
    with open(path, encoding="utf-8") as f:
        lines = prose(f.read())
    cache = {}

    def heads(p):
        if p not in cache:
            cache[p] = headings(p)
        return cache[p]

    for no, line in enumerate(lines, 1):
        where = "%s:%d" % (rel, no)
        for m in LINK.finditer(line):
            target = m.group(1)
            if re.match(r"[a-z][a-z0-9+.-]*:", target):  # https:, mailto:
                continue
            file, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(base, file)) if file else path
            if not os.path.exists(dest):
                out.append("%s: link to '%s': no such file" % (where, target))
                continue
            if anchor:
                if not dest.endswith(".md"):
                    out.append("%s: link to '%s': an anchor into a file that is not Markdown" % (where, target))
                elif anchor not in heads(dest)[1]:
                    out.append("%s: link to '%s': %s has no heading with anchor '#%s'"
                               % (where, target, os.path.relpath(dest, SOURCE), anchor))
    text = "\n".join(lines)
    line_of = lambda m: "%s:%d" % (rel, text.count("\n", 0, m.start()) + 1)
    for m in NAMED.finditer(text):
        name, section = m.group(1), " ".join(m.group(2).split())
        dest = find_document(name, base)
        if dest is None:
            out.append("%s: section \"%s\" of '%s': no such document" % (line_of(m), section, name))
        elif not names_heading(heads(dest)[0], section):
            out.append("%s: section \"%s\" of %s: no such heading" % (line_of(m), section, os.path.relpath(dest, SOURCE)))
    for m in OWN.finditer(text):
        section = " ".join(m.group(1).split())
        if not names_heading(heads(path)[0], section):
            out.append("%s: section \"%s\": no such heading here" % (line_of(m), section))
    return sorted(out, key=lambda p: int(p.split(":")[1]))


class DocLinksTest(unittest.TestCase):
    def test_every_link_and_section_reference_resolves(self):
        found = [p for d in documents() for p in problems(d)]
        self.assertEqual(found, [], "\n" + "\n".join(found))

    def test_readme_is_a_guide_not_a_log(self):
        with open(os.path.join(SOURCE, "README.md"), encoding="utf-8") as f:
            n = len(f.read().splitlines())
        self.assertLessEqual(n, README_MAX_LINES, "README.md has %d lines" % n)

    def test_the_readme_test_command_is_what_ci_runs(self):
        """The README's two commands: the second is .ci/run's command word for word, and the first
        sets up the same way."""
        with open(os.path.join(SOURCE, ".ci", "run"), encoding="utf-8") as f:
            run = f.read()
        ci = " ".join(run[run.index('cd "$(dirname "$0")/.."') :].split("\n", 1)[1].split())
        with open(os.path.join(SOURCE, "README.md"), encoding="utf-8") as f:
            readme = f.read()
        blocks = [" ".join(b.split()) for b in re.findall(r"```\n(.*?)```", readme, re.S)]
        self.assertEqual(blocks[1], ci, "README's second command is not .ci/run's")
        setup = "./scripts/install-deps.sh && ./scripts/build.sh && "
        self.assertTrue(ci.startswith(setup), ci)
        self.assertTrue(blocks[0].startswith(setup + "./build/bin/enavi eval"), blocks[0])

    def test_the_checker_finds_what_it_is_for(self):
        """The checker itself, on a planted document: a missing file, a missing anchor, a section
        named in words that no heading has, and their correct forms, which pass."""
        import tempfile
        global SOURCE
        saved = SOURCE
        with tempfile.TemporaryDirectory() as tmp:
            os.makedirs(os.path.join(tmp, "docs"))
            with open(os.path.join(tmp, "docs", "b.md"), "w") as f:
                f.write("# B\n\n## Time: two clocks\n\n## Training (2026-12-04)\n\n## 3. Topics\n")
            with open(os.path.join(tmp, "README.md"), "w") as f:
                f.write("# A\n\n## One flight\n\n"
                        "[ok](docs/b.md#time-two-clocks), [ok](#one-flight), docs/b.md, \"Training\", docs/b.md, \"Topics\",\n"
                        "README, \"One flight\", section \"One flight\", `README, \"Nowhere\"` in code,\n"
                        "[x](docs/none.md) [y](docs/b.md#nowhere) [z](#nowhere)\n"
                        "docs/b.md, \"Train\" and README, \"Missing\" and section \"Gone\", README,\n"
                        "\"One\nflight\" wrapped, docs/b.md, \"Time:\ntwo clocks\", README, \"Wrapped\nmissing\"\n"
                        "```\n[in](a/code/block.md)\n```\n")
            try:
                SOURCE = tmp
                found = problems(os.path.join(tmp, "README.md"))
            finally:
                SOURCE = saved
        self.assertEqual(len(found), 7, "\n".join(found))
        self.assertTrue(all(p.startswith(("README.md:7:", "README.md:8:", "README.md:11:")) for p in found), found)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]], verbosity=2)
