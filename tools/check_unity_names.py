#!/usr/bin/env python3
"""Fails when two source files of one library give a file-local name twice.

The unity build (VIO_UNITY_BUILD, the default) compiles a library's src/*.cc
files together, several to one translation unit. Names with internal linkage
(declared inside `namespace {` or `static` at namespace scope) are then no
longer private to their file: two files that both define `kColumns` compile
apart and fail together. Which files share a unity source depends on the batch
size and on the file list, so this check holds every pair of a library's
files to the rule, not only the pairs that share a unity source today.

usage: check_unity_names.py [ROOT]   (default: the repository holding this file)
Prints each clash as `library: name in file:line and file:line`; exit 1 when
there is any, 0 when none, 2 when ROOT has no library.
"""
import collections
import pathlib
import re
import sys

IDENT = r"[A-Za-z_]\w*"
KEYWORDS = {"const", "constexpr", "static", "inline", "struct", "class", "enum", "using", "template",
            "typename", "union", "operator", "return", "if", "for", "while", "switch", "namespace"}


def strip(text):
    """The source with comments, string and character literals blanked (line breaks kept)."""
    pattern = re.compile(r'//[^\n]*|/\*.*?\*/|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'', re.S)
    return pattern.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def declared_name(statement):
    """The name a namespace-scope declaration introduces, or None (forward declarations, using-directives)."""
    text = re.sub(r"\s+", " ", statement).strip()
    text = re.sub(r"^template ?<.*?> ?(?=[A-Za-z_])", "", text)  # one level of template header
    # using-declarations and namespace aliases may be repeated in one scope
    if not text or re.match(r"(using [\w:]+ ?$|using namespace|namespace |static_assert|friend)", text):
        return None
    match = re.match(rf"(?:struct|class|union|enum(?: class| struct)?) ({IDENT})", text)
    if match:
        return match.group(1)
    match = re.match(rf"using ({IDENT}) ?=", text)
    if match:
        return match.group(1)
    head = re.split(r"=|\{", text, maxsplit=1)[0]
    paren = head.find("(")
    if paren >= 0:  # a function: the name before its parameter list, overloads told apart by their types
        candidates = re.findall(rf"(operator ?\S+?|{IDENT}) ?$", head[:paren])
        if candidates and candidates[-1] not in KEYWORDS:
            return candidates[-1] + parameter_types(head[paren:])
    else:  # a variable: the last identifier before its initializer or array bound
        candidates = re.findall(rf"({IDENT}) ?(?:\[[^\]]*\] ?)*$", head)
    name = candidates[-1] if candidates else None
    return None if name in KEYWORDS else name


def parameter_types(text):
    """`(type, type)` of a parameter list that starts `text`: names and default values dropped."""
    depth, end = 0, len(text)
    for i, char in enumerate(text):
        depth += {"(": 1, "<": 1, ")": -1, ">": -1}.get(char, 0)
        if depth == 0:
            end = i
            break
    params, depth, current = [], 0, ""
    for char in text[1:end]:
        depth += {"(": 1, "<": 1, ")": -1, ">": -1}.get(char, 0)
        if char == "," and depth == 0:
            params.append(current)
            current = ""
        else:
            current += char
    params.append(current)
    types = []
    for param in params:
        param = param.split("=")[0].strip()
        if re.search(rf"[\w>&*] +{IDENT}$", param):
            param = re.sub(rf" *{IDENT}$", "", param)
        types.append(param.replace(" ", ""))
    return "(" + ", ".join(t for t in types if t) + ")"


def internal_names(path):
    """(name, line) for each name `path` declares with internal linkage at namespace scope."""
    text = strip(path.read_text())
    names = []
    scopes = []  # one entry per open brace: "anon", "namespace" or "other"
    start = 0  # where the current statement began
    for match in re.finditer(r"[{};]", text):
        char, pos = match.group(0), match.start()
        statement = text[start:pos]
        at_namespace_scope = all(scope != "other" for scope in scopes)
        internal = at_namespace_scope and (
            (scopes and scopes[-1] == "anon") or re.match(r"\s*static\b", statement))
        if char == "{":
            if re.search(r"\bnamespace\s*$", statement):
                scopes.append("anon")
                start = pos + 1
                continue
            if re.search(rf"\bnamespace\s+[\w:]+\s*$", statement) or re.search(r'extern\s*$', statement):
                scopes.append("namespace")
                start = pos + 1
                continue
            if internal:
                name = declared_name(statement)
                if name:
                    names.append((name, text.count("\n", 0, pos - len(statement.lstrip())) + 1))
            scopes.append("other")
            start = pos + 1
        elif char == "}":
            if scopes:
                scopes.pop()
            start = pos + 1
        else:  # ";": a variable or alias (a function declared here without its body names nothing new)
            if internal and "(" not in statement.split("=")[0]:
                name = declared_name(statement)
                if name:
                    names.append((name, text.count("\n", 0, pos - len(statement.lstrip())) + 1))
            start = pos + 1
    return names


def libraries(root):
    """Each library folder: a CMakeLists.txt beside a src/ with .cc files."""
    for cmake in sorted(root.glob("**/CMakeLists.txt")):
        src = cmake.parent / "src"
        if src.is_dir() and any(src.glob("*.cc")) and "build" not in cmake.parts[len(root.parts):]:
            yield cmake.parent


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
    clashes = 0
    count = 0
    for library in libraries(root):
        count += 1
        seen = collections.defaultdict(list)
        for source in sorted((library / "src").glob("*.cc")):
            for name, line in internal_names(source):
                seen[name].append(f"{source.relative_to(root)}:{line}")
        for name, places in sorted(seen.items()):
            files = {place.rsplit(":", 1)[0] for place in places}
            if len(files) > 1:
                print(f"{library.relative_to(root)}: '{name}' is file-local in {' and '.join(places)}"
                      " (one unity source may hold both: give it a name that says what it is)")
                clashes += 1
    if count == 0:
        print(f"check_unity_names: no library under {root}", file=sys.stderr)
        return 2
    if clashes:
        print(f"check_unity_names: {clashes} file-local name(s) defined in two files of one library", file=sys.stderr)
        return 1
    print(f"check_unity_names: {count} libraries, every file-local name is defined in one file of its library")
    return 0


if __name__ == "__main__":
    sys.exit(main())
