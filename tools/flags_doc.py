#!/usr/bin/env python3
"""docs/flags.md against `vio <command> --help`: every flag, its type, default and valid range.

usage: flags_doc.py --vio=BUILD/bin/vio [--write] [--self_test] DOCS_FLAGS_MD

  (default)    check: exit 1 and name each flag that is missing from the doc, documented but
               gone from --help, or documented with another type, default or range
  --write      (re)write the doc from --help (its tables and their descriptions)
  --self_test  also check that the comparison catches a missing, a removed and a changed flag

The doc has one section per command (`## vio run`, ...) with a table of the flags only that
command lists, and one section per group of flags several commands share (`## Run configuration`,
`## Logging`); a command's section names the groups it takes ("Also takes: [Run configuration]...").
CTest runs the check (test `flags_doc`, label unit).
"""
import argparse
import re
import subprocess
import sys

COMMANDS = ["run", "simulate", "eval", "verify", "sweep", "convert", "imagestats", "matchcheck"]
# --help's heading of a shared group -> the doc's section title.
GROUPS = {"run configuration": "Run configuration", "logging": "Logging"}
FLAG_LINE = re.compile(r"^  --([A-Za-z0-9_]+)=(.*) \(([a-z0-9]+)\)$")
VALID = re.compile(r"\s*valid: (\S.*?)\s*$")
CHOICES = re.compile(r"\s*\{([^{}]+)\}\s*$")


class Flag:
    def __init__(self, name, type_, default, valid, description):
        self.name, self.type, self.default, self.valid, self.description = name, type_, default, valid, description

    def key(self):
        return (self.type, self.default, self.valid)


def split_range(description):
    """(description without its range, range): 'valid: [1, inf)' or the choices 'a|b'."""
    match = CHOICES.search(description)
    if match:
        return description[:match.start()], "one of " + ", ".join(match.group(1).split("|"))
    match = VALID.search(description)
    if match:
        return description[:match.start()], match.group(1)
    return description, ""


def parse_help(text):
    """{group: {name: Flag}}; group "" is the command's own flags."""
    groups, group, current = {}, None, None
    for line in text.splitlines():
        if line.endswith(":") and not line.startswith(" "):
            heading = line[:-1].split(" (")[0]
            group = "" if heading == "flags" else heading if heading in GROUPS else None
            if group is not None:
                groups.setdefault(group, {})
            current = None
            continue
        match = FLAG_LINE.match(line)
        if match and group is not None:
            current = Flag(match.group(1), match.group(3), match.group(2), "", "")
            groups[group][current.name] = current
        elif current is not None and line.startswith("      "):
            current.description += (" " if current.description else "") + line.strip()
    for flags in groups.values():
        for flag in flags.values():
            flag.description, flag.valid = split_range(flag.description)
            flag.description = flag.description.strip()
    return groups


def help_of(vio, command):
    result = subprocess.run([vio, command, "--help"], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"flags_doc: `{vio} {command} --help` exited {result.returncode}:\n{result.stderr}")
    return parse_help(result.stdout)


def cell(text):
    return text.replace("|", "\\|")


def uncell(text):
    return text.strip().replace("\\|", "|")


def default_cell(default):
    return "(empty)" if default == "" else f"`{cell(default)}`"


def table(flags):
    lines = ["| flag | type | default | valid | what |", "|---|---|---|---|---|"]
    for flag in flags.values():
        lines.append(f"| `--{flag.name}` | {flag.type} | {default_cell(flag.default)} | {cell(flag.valid)} | "
                     f"{cell(flag.description)} |")
    return "\n".join(lines)


INTRO = """# Flags

Every flag of every `vio` command, as `vio <command> --help` prints it: type, default and valid range
(`valid` is the range the value is checked against; values outside it are an error that names the flag).
Each flag of the run configuration is also a key of the `--config` YAML (`config/euroc_stereo.yaml` has
every key, by section); the flag wins over the file.

This page is checked against `--help` by the test `flags_doc` (`tools/flags_doc.py`): a flag missing here,
a flag documented here that no command has, or a different type, default or range fails it. After adding
or changing a flag, add or fix its row (or regenerate the page: `python3 tools/flags_doc.py
--vio=build/bin/vio --write docs/flags.md`).
"""


def anchor(title):
    return title.lower().replace(" ", "-")


def render(helps):
    """The doc for {command: groups} (helps of every command)."""
    parts, shared = [INTRO], {}
    for command in COMMANDS:
        groups = helps[command]
        parts.append(f"## vio {command}\n")
        parts.append(table(groups.get("", {})) + "\n")
        taken = [GROUPS[g] for g in GROUPS if g in groups]
        if taken:
            parts.append("Also takes: " + ", ".join(f"[{t}](#{anchor(t)})" for t in taken) + ".\n")
        for group in GROUPS:
            if group in groups:
                shared.setdefault(group, groups[group])
    for group, title in GROUPS.items():
        parts.append(f"## {title}\n")
        parts.append(table(shared.get(group, {})) + "\n")
    return "\n".join(parts)


def parse_doc(text):
    """{section title: {name: Flag}} and {command: [group titles it takes]}."""
    sections, takes, title = {}, {}, None
    for line in text.splitlines():
        if line.startswith("## "):
            title = line[3:].strip()
            sections.setdefault(title, {})
        elif title and line.startswith("Also takes:"):
            takes[title] = re.findall(r"\[([^\]]+)\]", line)
        elif title and line.startswith("| `--"):
            cells = [uncell(c) for c in re.split(r"(?<!\\)\|", line)[1:-1]]
            if len(cells) != 5:
                continue
            name = cells[0].strip("`").lstrip("-")
            default = "" if cells[2] == "(empty)" else cells[2].strip("`")
            sections[title][name] = Flag(name, cells[1], default, cells[3], cells[4])
    return sections, takes


def describe(flag):
    return f"type {flag.type}, default {default_cell(flag.default)}, valid {flag.valid or '(none)'}"


def compare_flags(helped, documented, where, origin, problems):
    """Appends to `problems` (message -> commands) how the doc's table `where` differs from --help's flags."""
    for name, flag in helped.items():
        if name not in documented:
            row = table({name: flag}).splitlines()[-1]
            problems.setdefault(f"--{name} is in {origin} but missing from docs/flags.md, section \"{where}\"; "
                                f"add the row:\n    {row}", None)
        elif documented[name].key() != flag.key():
            problems.setdefault(f"--{name}: docs/flags.md, section \"{where}\", says {describe(documented[name])}; "
                                f"{origin} says {describe(flag)}", None)
    for name in documented:
        if name not in helped:
            problems.setdefault(f"--{name} is documented in docs/flags.md, section \"{where}\", but {origin} "
                                f"does not list it: remove its row (or restore the flag)", None)


def compare(helps, doc_text):
    """Every difference between the doc and the helps, as messages (empty: they agree)."""
    sections, takes = parse_doc(doc_text)
    problems, compared = {}, {}
    for command in COMMANDS:
        title, origin = f"vio {command}", f"`vio {command} --help`"
        if title not in sections:
            problems.setdefault(f"docs/flags.md has no section \"## {title}\" (the flags of {origin})", None)
            continue
        groups = helps[command]
        compare_flags(groups.get("", {}), sections[title], title, origin, problems)
        wanted = [GROUPS[g] for g in GROUPS if g in groups]
        if sorted(wanted) != sorted(takes.get(title, [])):
            problems.setdefault(f"docs/flags.md, section \"{title}\": its line \"Also takes: ...\" names "
                                f"{takes.get(title, [])}; {origin} lists the groups {wanted}", None)
        for group, group_title in GROUPS.items():
            # A shared group is compared once, unless another command's --help lists it differently.
            if group in groups and {f: v.key() for f, v in groups[group].items()} != compared.get(group):
                compared.setdefault(group, {f: v.key() for f, v in groups[group].items()})
                compare_flags(groups[group], sections.get(group_title, {}), group_title,
                              f"{origin} (\"{group}\")", problems)
    return list(problems)


def self_test(helps):
    """The comparison finds nothing on the rendered doc and each planted difference on a changed one."""
    doc = render(helps)
    assert compare(helps, doc) == [], compare(helps, doc)
    run = helps["run"][""]
    name = next(iter(run))
    removed = "\n".join(l for l in doc.splitlines() if not l.startswith(f"| `--{name}` "))
    changed = doc.replace("| `--window_size` | int32 | `10` |", "| `--window_size` | int32 | `12` |")
    added = doc.replace("## vio simulate\n", "## vio simulate\n\n| `--no_such_flag` | bool | `false` | | gone |\n")
    for text, needle in [(removed, f"--{name} is in `vio run --help` but missing"),
                         (changed, "--window_size: docs/flags.md, section \"Run configuration\", says type int32, "
                                   "default `12`"),
                         (added, "--no_such_flag is documented")]:
        found = [p for p in compare(helps, text) if p.startswith(needle)]
        assert found, f"self test: no problem starting with {needle!r}"
    print("flags_doc: self test passed (a missing, a changed and a stale flag are each reported)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vio", required=True)
    parser.add_argument("--write", action="store_true")
    parser.add_argument("--self_test", action="store_true")
    parser.add_argument("doc")
    args = parser.parse_args()
    helps = {command: help_of(args.vio, command) for command in COMMANDS}
    if args.self_test:
        self_test(helps)
    if args.write:
        with open(args.doc, "w") as f:
            f.write(render(helps))
        print(f"flags_doc: wrote {args.doc}")
        return 0
    with open(args.doc) as f:
        problems = compare(helps, f.read())
    for problem in problems:
        print(f"{args.doc}: {problem}")
    if problems:
        print(f"flags_doc: {len(problems)} difference(s) between {args.doc} and `vio <command> --help`; fix the "
              f"rows named above (or regenerate: python3 tools/flags_doc.py --vio=build/bin/vio --write {args.doc})")
        return 1
    print(f"flags_doc: {args.doc} agrees with --help of {len(COMMANDS)} commands")
    return 0


if __name__ == "__main__":
    sys.exit(main())
