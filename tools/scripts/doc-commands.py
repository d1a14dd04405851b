#!/usr/bin/env python3
"""Runs the commands of BENCHMARKS.md as written, section by section (standard library only).

A section is a `## ` heading with its `### ` subsections. Its code (blocks indented by four
spaces after a blank line, and shell ``` fences) runs as one bash script (`set -euo pipefail`),
in order, in a fresh folder `target/doc-commands/SLUG/` that links the repository's `samples`,
`tools`, `web`, `geometry` and `pipeline`, so that a command reads `samples/teatime.glb` as a
reader in the repository root would and writes its outputs beside the others of its section.
`hce` and `gen-samples` are the release binaries (`cargo build --release -p hce-tools -p
hce-samples`, done first unless --no-build), put first on PATH; the real meshes come from
$HCE_EXTRA_MESHES (default ../shared/meshes beside the repository); `osd_loop`
(shared/tools/osd_loop.cpp) must be on PATH for the sections that name it.

Usage:
    tools/scripts/doc-commands.py --list                 # the sections and their commands
    tools/scripts/doc-commands.py [--no-build] [SLUG ...]   # run these sections (default all)
    tools/scripts/doc-commands.py --skip SLUG [...]      # all but these

SLUG is a section's anchor (`baker-scaling`) or a unique prefix of it. Each section's output
goes to target/doc-commands/SLUG/log.txt; a summary line per section (passed or failed, and
its seconds) is printed as it ends and again at the end. Exits 1 when a section failed.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LINKED = ["samples", "tools", "web", "geometry", "pipeline"]


def slug(title):
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    s = title.strip().lower()
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def sections(text):
    """[(slug, title, script)] for each `## ` section that has code, in file order."""
    out = []
    title, lines = None, []
    fenced = shell = False
    prev_blank = True
    in_indented = False

    def close():
        if title is not None and any(l.strip() for l in lines):
            out.append((slug(title), title, "\n".join(lines) + "\n"))

    for line in text.splitlines():
        if not fenced and line.startswith("## "):
            close()
            title, lines = line[3:], []
            prev_blank, in_indented = True, False
            continue
        if line.lstrip().startswith("```"):
            if not fenced:
                # Only shell fences are commands; a ```toml or ```text block is data.
                lang = line.lstrip()[3:].strip()
                shell = lang in ("", "sh", "bash", "shell")
            fenced = not fenced
            continue
        if fenced:
            if shell:
                lines.append(line)
            continue
        if line.startswith("    ") and (prev_blank or in_indented) and line.strip():
            in_indented = True
            lines.append(line[4:])
        elif not line.strip():
            prev_blank = True
            if in_indented:
                lines.append("")
            continue
        else:
            in_indented = False
        prev_blank = False
    close()
    return out


def pick(all_sections, wanted):
    """The sections whose slug is, or uniquely starts with, each of `wanted`."""
    chosen = []
    for w in wanted:
        exact = [s for s in all_sections if s[0] == w]
        hits = exact or [s for s in all_sections if s[0].startswith(w)]
        if len(hits) != 1:
            names = ", ".join(s[0] for s in hits) or "none"
            sys.exit(f"doc-commands: '{w}' names {len(hits)} sections ({names}); --list shows them")
        chosen.append(hits[0])
    return chosen


def run(section, env):
    name, title, script = section
    work = ROOT / "target" / "doc-commands" / name
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)
    for d in LINKED:
        (work / d).symlink_to(ROOT / d)
    log = work / "log.txt"
    start = time.monotonic()
    with open(log, "w") as f:
        f.write(f"# {title}\n{script}\n# output\n")
        f.flush()
        status = subprocess.run(
            ["bash", "-euo", "pipefail", "-c", script],
            cwd=work, env=env, stdout=f, stderr=subprocess.STDOUT,
        ).returncode
    seconds = time.monotonic() - start
    verdict = "passed" if status == 0 else f"FAILED (status {status}; see {log.relative_to(ROOT)})"
    line = f"{name}: {verdict}, {seconds:.0f} s"
    print(line, flush=True)
    return status == 0, line


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("slugs", nargs="*")
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--skip", nargs="+", default=[])
    ap.add_argument("--no-build", action="store_true")
    ap.add_argument("--file", default=str(ROOT / "BENCHMARKS.md"))
    args = ap.parse_args()

    found = sections(Path(args.file).read_text())
    chosen = pick(found, args.slugs) if args.slugs else found
    skipped = {s[0] for s in pick(found, args.skip)}
    chosen = [s for s in chosen if s[0] not in skipped]
    if args.list:
        for name, title, script in chosen:
            print(f"== {name} ({title})\n{script}")
        return 0

    env = dict(os.environ)
    if "HCE_EXTRA_MESHES" not in env:
        shared = ROOT.parent / "shared" / "meshes"
        if not shared.is_dir():
            sys.exit("doc-commands: set HCE_EXTRA_MESHES to the folder of the real test meshes")
        env["HCE_EXTRA_MESHES"] = str(shared)
    env["PATH"] = f"{ROOT / 'target' / 'release'}{os.pathsep}{env.get('PATH', '')}"
    if not args.no_build:
        subprocess.run(
            ["cargo", "build", "--release", "-q", "-p", "hce-tools", "-p", "hce-samples"],
            cwd=ROOT, check=True,
        )
    results = [run(s, env) for s in chosen]
    print("\n".join(["== summary"] + [line for _, line in results]))
    return 0 if all(ok for ok, _ in results) else 1


if __name__ == "__main__":
    sys.exit(main())
