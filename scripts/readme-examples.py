#!/usr/bin/env python3
"""Runs the examples of README.md and compares what they print with what the
README shows (review finding 24: example outputs went stale unnoticed).

An example is a fenced block whose lines start with "$ " (a command; a line
ending in a backslash continues it) followed by the lines it prints. Each block
runs in a fresh scratch folder that holds `build/fdsid` (the binary under
test) and links to the repository's `data`, `fixtures` and `docs`; its commands
run in order through bash, stdout and stderr together, and each command's
output must equal the lines shown under it, line for line. A shown line "…"
stands for any number of lines (an elided part); "…" inside a line stands
for any text (a figure that differs between machines, which the README says). A command with no lines
under it is run for its effect (files the next commands read) and must exit
0; what it prints is not shown, so not compared.

Blocks that use the measured data beside the repository (../shared/, which a
clone alone does not have) run when that folder exists, with ../shared read
as its absolute path; without it they are skipped. Skipped too, and counted:
blocks with placeholders (MODEL.json …) and nothing shown, and blocks fenced
as ```sh or ```bash.

Usage: readme-examples.py FDSID_EXE [README.md]
Exit 0 when every example matches, 1 with a diff of each mismatch otherwise.
"""
import os
import re
import subprocess
import sys
import tempfile

ELLIPSIS = "…"


def blocks(text):
    """Yields (line number, fence info, lines) of each fenced block."""
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        if lines[i].startswith("```"):
            info = lines[i][3:].strip()
            start = i + 1
            j = start
            while j < len(lines) and not lines[j].startswith("```"):
                j += 1
            yield start, info, lines[start:j]
            i = j + 1
        else:
            i += 1


def examples(block):
    """(command, expected output lines) pairs of one block."""
    out = []
    i = 0
    while i < len(block):
        line = block[i]
        if not line.startswith("$ "):
            return None  # prose or output before any command: not a transcript
        cmd = line[2:]
        while cmd.endswith("\\") and i + 1 < len(block):
            i += 1
            cmd = cmd[:-1] + " " + block[i].strip()
        i += 1
        expected = []
        while i < len(block) and not block[i].startswith("$ "):
            expected.append(block[i])
            i += 1
        out.append((cmd, expected))
    return out


def line_matches(expected, actual):
    """Equality, where "…" inside a line matches any text (a figure that
    differs between machines, said beside the example)."""
    if ELLIPSIS not in expected:
        return expected == actual
    pattern = ".*".join(re.escape(part) for part in expected.split(ELLIPSIS))
    return re.fullmatch(pattern, actual) is not None


def matches(expected, actual):
    """Line-for-line equality, "…" matching any run of lines."""
    if not expected:
        return not actual
    if expected[0] == ELLIPSIS:
        return any(matches(expected[1:], actual[k:]) for k in range(len(actual) + 1))
    return bool(actual) and line_matches(expected[0], actual[0]) and matches(expected[1:], actual[1:])


def main():
    exe = os.path.abspath(sys.argv[1])
    readme = sys.argv[2] if len(sys.argv) > 2 else os.path.join(os.path.dirname(__file__), "..", "README.md")
    source = os.path.dirname(os.path.abspath(readme))
    text = open(readme, encoding="utf-8").read()
    shared = os.path.realpath(os.path.join(source, "..", "shared"))
    ran = skipped = failed = 0
    for start, info, block in blocks(text):
        ex = examples(block)
        if not ex or not any("./build/fdsid" in cmd for cmd, _ in ex):
            continue
        uses_shared = any("../shared" in cmd for cmd, _ in ex)
        placeholders = any(w in cmd for cmd, _ in ex for w in ("MODEL.json", "DATA.csv", "META.json"))
        if info in ("sh", "bash") or (uses_shared and not os.path.isdir(shared)) or placeholders:
            skipped += 1
            continue
        ex = [(cmd.replace("../shared", shared), expected) for cmd, expected in ex]
        with tempfile.TemporaryDirectory(prefix="fdsid-readme-") as work:
            os.makedirs(os.path.join(work, "build"))
            os.symlink(exe, os.path.join(work, "build", "fdsid"))
            for d in ("data", "fixtures", "docs"):
                os.symlink(os.path.join(source, d), os.path.join(work, d))
            env = ""  # assignments (F=…) earlier in the block hold for the commands after them
            for cmd, expected in ex:
                ran += 1
                if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*=\S+", cmd.strip()):
                    env += cmd.strip() + "; "
                p = subprocess.run(["bash", "-c", env + cmd], cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                   timeout=600)
                actual = p.stdout.decode("utf-8", "replace").rstrip("\n").split("\n")
                if actual == [""]:
                    actual = []
                shown = [l for l in expected]
                while shown and shown[-1] == "":
                    shown.pop()
                ok = (p.returncode == 0) if not shown else matches(shown, actual)
                if not ok:
                    failed += 1
                    print(f"README.md line {start}: $ {cmd}\n  exit {p.returncode}\n  shown:")
                    for l in shown:
                        print("    " + l)
                    print("  printed:")
                    for l in actual:
                        print("    " + l)
    print(f"README examples: {ran} commands run, {failed} differ from the README; {skipped} blocks skipped "
          f"(synopses with placeholders, scripts, or blocks on ../shared when {shared} is absent)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
