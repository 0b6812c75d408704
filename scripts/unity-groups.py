#!/usr/bin/env python3
"""Checks and plans the unity groups of lodbake_tests (tests/CMakeLists.txt, LODBAKE_TEST_UNITY_GROUPS).

  scripts/unity-groups.py          check: exit 1 naming the files of a group that define the same
                                   file-local name, and list the suite files that are in no group
  scripts/unity-groups.py --plan   print new groups (at most 8 files each) for the whole suite list,
                                   to paste into LODBAKE_TEST_UNITY_GROUPS

A group's files are compiled as one translation unit, so a helper, type, constant, `using` or macro
defined at file scope in two of them would collide or, worse, be picked up by the wrong file. The
names are found with regular expressions (top-level functions, types, k-constants anywhere, usings,
macros), which errs on the side of seeing a clash. A file with a global `using nlohmann::json` is
kept apart from every file that names `json` (a local `json` would shadow it under -Wshadow), and
a file with a `using namespace` of a nested namespace from files with other directives.
"""
import os
import re
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests")
FUNCTION = re.compile(r"^(?!TEST|INSTANTIATE|namespace|using|return|template|#)[A-Za-z_][\w:<>,\s\*&]*?[\s\*&]"
                      r"([A-Za-z_]\w*)\s*\(", re.M)
TYPE = re.compile(r"^(?:struct|class|enum class|enum|union)\s+([A-Za-z_]\w*)", re.M)
CONSTANT = re.compile(r"\b(?:constexpr|const)\s+[\w:<>]+\s+(k[A-Z]\w*)\b")
USING = re.compile(r"^using\s+(?:[\w:]+::)?(\w+)\s*[;=]", re.M)
MACRO = re.compile(r"^#define\s+(\w+)", re.M)
GLOBAL_JSON = re.compile(r"^using (nlohmann::json|json\s*=)", re.M)
DIRECTIVE = re.compile(r"^using namespace ([\w:]+);", re.M)


def cmake_text():
    with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
        return f.read()


def suite_files(text):
    block = text[text.index("add_executable(lodbake_tests"):]
    block = block[:block.index("\n)")]
    return [line.strip() for line in block.splitlines()[1:] if line.strip().endswith(".cpp")]


def current_groups(text):
    block = text[text.index("set(LODBAKE_TEST_UNITY_GROUPS"):]
    block = block[:block.index(")")]
    groups = [[]]
    for token in block.split()[2:]:
        if token == "#" or token.startswith("#"):
            continue
        if token == "--":
            groups.append([])
        elif token.endswith(".cpp"):
            groups[-1].append(token)
    return [g for g in groups if g]


def names_of(path):
    with open(os.path.join(ROOT, path)) as f:
        s = f.read()
    names = set(FUNCTION.findall(s)) | set(TYPE.findall(s)) | set(CONSTANT.findall(s)) | set(USING.findall(s))
    names |= set(MACRO.findall(s))
    names -= {"main", "json"}
    return names, bool(GLOBAL_JSON.search(s)), bool(re.search(r"\bjson\b", s)), set(DIRECTIVE.findall(s))


def clashes(a, b, info):
    (na, ga, ua, da), (nb, gb, ub, db) = info[a], info[b]
    shared = sorted(na & nb)
    if (ga and ub) or (gb and ua):
        shared.append("json")
    # `using namespace lodbake::scansim` next to another file's `using namespace lodbake` makes
    # names both namespaces define ambiguous (Vec3d): a nested directive only goes with itself.
    for x, y in ((da, db), (db, da)):
        if any("::" in d for d in x) and y and y != x:
            shared.append("using namespace " + ", ".join(sorted(x | y)))
            break
    return shared


def plan(files, info, size=8):
    order = sorted(files, key=lambda f: -sum(bool(clashes(f, o, info)) for o in files if o != f))
    groups = []
    for f in order:
        for g in groups:
            if len(g) < size and not any(clashes(f, o, info) for o in g):
                g.append(f)
                break
        else:
            groups.append([f])
    return groups


def main():
    text = cmake_text()
    files = suite_files(text)
    info = {f: names_of(f) for f in files}
    if "--plan" in sys.argv[1:]:
        for i, g in enumerate(plan(files, info)):
            if i:
                print("    --")
            line = "   "
            for f in g:
                if len(line) + 1 + len(f) > 110:
                    print(line)
                    line = "   "
                line += " " + f
            print(line)
        return 0
    failed = False
    grouped = set()
    for g in current_groups(text):
        for i, a in enumerate(g):
            if a not in info:
                print(f"unity-groups: {a} is not a source of lodbake_tests", file=sys.stderr)
                failed = True
                continue
            grouped.add(a)
            for b in g[i + 1:]:
                if b in info and clashes(a, b, info):
                    print(f"unity-groups: {a} and {b} share file-local names: {', '.join(clashes(a, b, info))}",
                          file=sys.stderr)
                    failed = True
    for f in files:
        if f not in grouped:
            print(f"unity-groups: {f} is in no group (compiled on its own)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
