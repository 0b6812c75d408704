#!/usr/bin/env python3
"""Checks every quoted #include of the baker and the runtime against the module table of
docs/architecture.md (the table whose header is `| module | headers | may depend on | owns |`).

Each source file belongs to a module:
  baker/src/<m>/...              -> <m>
  baker/include/lodbake/<m>/...  -> <m>   (headers directly in baker/include/lodbake/ -> core)
  baker/cli/...                  -> cli
  runtime/src/..., runtime/include/... -> runtime
  runtime/tools/..., runtime/examples/... -> tools

An include is resolved the way the build resolves it: "lodbake/..." and "lodrt/..." through the
public include folders, anything else next to the including file, then in the private include
folders (baker/src, runtime/src). Includes that resolve to no file of the tree are third-party and
ignored, unless the tree has the file elsewhere (an include path added for one file hides an
arrow between modules, so it is an error too). A file may include its own module and the modules its row lists under "may depend on"
(comma-separated; names that are not modules of the table, such as std or TBB, are ignored).

Fails (exit 1), printing one line per problem, when an include points to a module not listed in
its row (file:line), when a module has no row, when a row lists a module that comes later in the
table (the table must read top-down), or when modules or files include each other in a cycle.

usage: check-includes.py [SOURCE_ROOT]   (default: the folder above this script)
"""

import os
import re
import sys

INCLUDE_RE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
TABLE_HEADER_RE = re.compile(r'^\|\s*module\s*\|\s*headers\s*\|\s*may depend on\s*\|\s*owns\s*\|\s*$')
SOURCE_EXTENSIONS = ('.h', '.hpp', '.cpp', '.cc', '.inl')
SCANNED = ('baker/src', 'baker/include', 'baker/cli', 'runtime')


def module_of(rel):
    """Module of a path relative to the source root, or None when it belongs to no module."""
    parts = rel.split('/')
    if parts[:2] == ['baker', 'src'] and len(parts) > 3:
        return parts[2]
    if parts[:3] == ['baker', 'include', 'lodbake']:
        return parts[3] if len(parts) > 4 else 'core'
    if parts[:2] == ['baker', 'cli']:
        return 'cli'
    if parts[0] == 'runtime' and len(parts) > 2:
        if parts[1] in ('src', 'include'):
            return 'runtime'
        if parts[1] in ('tools', 'examples'):
            return 'tools'
    return None


def parse_table(path):
    """Returns the modules in table order and, per module, the set of names its row may depend on."""
    with open(path, encoding='utf-8') as f:
        lines = f.read().splitlines()
    start = next((i for i, l in enumerate(lines) if TABLE_HEADER_RE.match(l)), None)
    if start is None:
        return None, None
    order, allowed = [], {}
    for line in lines[start + 2:]:
        if not line.startswith('|'):
            break
        cells = [c.strip() for c in line.strip().strip('|').split('|')]
        if len(cells) < 3:
            continue
        name = cells[0].strip('`* ')
        names = set()
        for token in re.split(r'[,;]', cells[2]):
            words = token.replace('`', ' ').split()
            if words:
                names.add(words[0])
        order.append(name)
        allowed[name] = names
    return order, allowed


def resolve(root, including_rel, target):
    """Path (relative to root) of the file `#include "target"` in `including_rel` names, or None."""
    candidates = []
    if target.startswith('lodbake/'):
        candidates.append('baker/include/' + target)
    elif target.startswith('lodrt/'):
        candidates.append('runtime/include/' + target)
    candidates.append(os.path.normpath(os.path.join(os.path.dirname(including_rel), target)))
    if including_rel.startswith('baker/'):
        candidates.append('baker/src/' + target)
    if including_rel.startswith('runtime/'):
        candidates.append('runtime/src/' + target)
    for c in candidates:
        if not c.startswith('..') and os.path.isfile(os.path.join(root, c)):
            return c.replace(os.sep, '/')
    return None


def find_cycle(graph):
    """One cycle of `graph` (node -> set of nodes) as a list of nodes, or None. Iterative DFS."""
    state = {}
    for start in sorted(graph):
        if state.get(start):
            continue
        stack = [(start, iter(sorted(graph.get(start, ()))))]
        path = [start]
        state[start] = 1
        while stack:
            node, children = stack[-1]
            child = next(children, None)
            if child is None:
                state[node] = 2
                stack.pop()
                path.pop()
            elif state.get(child) == 1:
                return path[path.index(child):] + [child]
            elif not state.get(child):
                state[child] = 1
                path.append(child)
                stack.append((child, iter(sorted(graph.get(child, ())))))
    return None


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..'))
    table_path = os.path.join(root, 'docs', 'architecture.md')
    order, allowed = parse_table(table_path)
    if order is None:
        print(f'{table_path}: no table with the columns | module | headers | may depend on | owns |')
        return 1
    problems = []
    rank = {m: i for i, m in enumerate(order)}
    for m in order:
        for dep in sorted(allowed[m]):
            if dep in rank and rank[dep] >= rank[m]:
                problems.append(f'docs/architecture.md: module {m} may depend on {dep}, which is not above it in the table')

    files = []
    for top in SCANNED:
        for dirpath, dirnames, filenames in os.walk(os.path.join(root, top)):
            dirnames.sort()
            for name in sorted(filenames):
                if name.endswith(SOURCE_EXTENSIONS):
                    files.append(os.path.relpath(os.path.join(dirpath, name), root).replace(os.sep, '/'))

    missing = set()
    module_graph, file_graph = {}, {}
    for rel in files:
        src_module = module_of(rel)
        if src_module is None:
            continue
        with open(os.path.join(root, rel), encoding='utf-8', errors='replace') as f:
            for number, line in enumerate(f, 1):
                m = INCLUDE_RE.match(line)
                if not m:
                    continue
                target = resolve(root, rel, m.group(1))
                if target is None:
                    elsewhere = [f for f in files if f.endswith('/' + m.group(1))]
                    if elsewhere:
                        problems.append(f'{rel}:{number}: "{m.group(1)}" is {elsewhere[0]}, reached only through '
                                        f'an include path added for it')
                    continue  # third-party
                file_graph.setdefault(rel, set()).add(target)
                dst_module = module_of(target)
                if dst_module is None or dst_module == src_module:
                    continue
                module_graph.setdefault(src_module, set()).add(dst_module)
                where = f'{rel}:{number}'
                for mod in (src_module, dst_module):
                    if mod not in allowed and mod not in missing:
                        missing.add(mod)
                        problems.append(f'{where}: module {mod} has no row in the module table of docs/architecture.md')
                if src_module in allowed and dst_module in allowed and dst_module not in allowed[src_module]:
                    problems.append(f'{where}: {src_module} includes "{m.group(1)}" of module {dst_module}, '
                                    f'which is not in its "may depend on" column')

    cycle = find_cycle(module_graph)
    if cycle:
        problems.append('module include cycle: ' + ' -> '.join(cycle))
    cycle = find_cycle(file_graph)
    if cycle:
        problems.append('file include cycle: ' + ' -> '.join(cycle))
    for p in problems:
        print(p)
    if problems:
        return 1
    print(f'{len(files)} files, {len(order)} modules: every include points down the module table')
    return 0


if __name__ == '__main__':
    sys.exit(main())
