#!/usr/bin/env python3
"""Find import cycles between the module files of each crate under crates/*/src.

Every .rs file is a node, named by its module path: src/lib.rs (or src/main.rs) is the crate
root, src/a.rs and src/a/mod.rs are `a`, src/a/b.rs is `a::b`. Modules written inline
(`mod tests { ... }`) belong to the file they are written in.

An edge A -> B means that code in A names an item of B through a path:
  - `crate::b::Item`, `super::Item`, `self::b::Item`, or `b::Item` where `b` is a child module
    of A or a name A imports, in a `use` declaration or anywhere else in the code;
  - a path naming an item that a module only re-exports (`pub use`, a private `use` seen by the
    module's children, or a glob `use x::*`) leads on to the module that defines the item, so
    `use crate::Grid` in a child of lib.rs is an edge to lib.rs only if lib.rs defines `Grid`;
  - `use x::*` is an edge to x; a `use` naming a module itself (`use crate::fit;`) is not, but
    every path through that name is.
The declaration `mod child;` is not an import: a parent and its child form a cycle only if each
names the other's items. Paths into other crates are not edges. Test code counts as any other.

The script prints every strongly connected component of more than one file in each crate, each
file with the files of the component it imports from (and the first path that does), and exits 1
if there is one.

Usage: python3 tools/check_cycles.py [crate directory ...]   (default: crates/*)
       python3 tools/check_cycles.py --self-test
"""

import re
import sys
from pathlib import Path

# Comments, string and character literals: removed before the code is split into tokens.
NOISE = re.compile(
    r"//[^\n]*|/\*.*?\*/"
    r"|\bb?r(#*)\".*?\"\1"
    r"|(?:\bb)?\"(?:\\.|[^\"\\])*\""
    r"|(?:\bb)?'(?:\\u\{[0-9a-fA-F]+\}|\\.|[^\\'\n])'",
    re.S,
)
TOKEN = re.compile(r"[A-Za-z_]\w*|::|\S")
ITEM_KEYWORDS = {"fn", "struct", "enum", "trait", "type", "const", "static", "union", "mod"}
KEYWORDS = ITEM_KEYWORDS | {"pub", "crate", "self", "super", "Self", "use", "impl", "let", "as"}


def is_name(token):
    return token[0].isalpha() or token[0] == "_"


def tokens(text):
    return TOKEN.findall(NOISE.sub(" ", text))


def module_path(src, file):
    """The module path of a file under src: () for the crate root."""
    parts = list(file.relative_to(src).with_suffix("").parts)
    if parts[-1] == "mod" or (len(parts) == 1 and parts[0] in ("lib", "main")):
        parts.pop()
    return tuple(parts)


class Crate:
    def __init__(self, files):
        """files: {module path: source text}."""
        self.file_of = {}  # module path (inline modules too) -> the module path of its file
        self.uses = {}  # module -> {name: (module the use is written in, raw path)}
        self.globs = {}  # module -> [(module, raw path)]
        self.defined = {}  # module -> names of the items it defines
        self.refs = []  # (file, module, raw path, kind: "use", "glob" or "path")
        for mod in files:
            self._add_module(mod, mod)
        for mod, text in files.items():
            self._parse(mod, tokens(text))

    def _add_module(self, mod, file):
        self.file_of[mod] = file
        self.uses.setdefault(mod, {})
        self.globs.setdefault(mod, [])
        self.defined.setdefault(mod, set())

    def _parse(self, file, toks):
        inline = []  # (module path, brace depth at which it closes)
        depth, i = 0, 0
        while i < len(toks):
            t = toks[i]
            mod = inline[-1][0] if inline else file
            if t == "{":
                depth += 1
            elif t == "}":
                depth -= 1
                if inline and inline[-1][1] == depth:
                    inline.pop()
            elif t == "mod" and i + 2 < len(toks) and toks[i + 2] == "{":
                inline.append((mod + (toks[i + 1],), depth))
                self._add_module(mod + (toks[i + 1],), file)
            elif t == "use":
                end = toks.index(";", i)
                for path, alias in use_tree(toks[i + 1 : end]):
                    if alias == "*":
                        self.globs[mod].append((mod, path))
                    elif alias != "_":
                        self.uses[mod][alias] = (mod, path)
                    self.refs.append((file, mod, path, "glob" if alias == "*" else "use"))
                i = end
            elif t in ITEM_KEYWORDS and i + 1 < len(toks) and toks[i + 1] not in KEYWORDS:
                self.defined[mod].add(toks[i + 1])
            elif t == "macro_rules" and i + 2 < len(toks):
                self.defined[mod].add(toks[i + 2])
            elif is_name(t) and toks[i + 1 : i + 2] == ["::"] and (i == 0 or toks[i - 1] != "::"):
                path = [t]
                while toks[i + 1 : i + 2] == ["::"] and i + 2 < len(toks) and is_name(toks[i + 2]):
                    path.append(toks[i + 2])
                    i += 2
                self.refs.append((file, mod, tuple(path), "path"))
            i += 1

    def absolute(self, mod, path, seen=()):
        """The crate-relative path of `path` as written in module `mod`; None outside the crate."""
        head, rest = path[0], path[1:]
        if head == "crate":
            return rest
        if head == "self":
            return mod + rest
        if head == "super":
            return self.absolute(mod[:-1], ("self",) + rest, seen) if mod else None
        if mod + (head,) in self.file_of:
            return mod + path
        if head in self.uses.get(mod, {}) and (mod, head) not in seen:
            use_mod, use_path = self.uses[mod][head]
            base = self.absolute(use_mod, use_path, seen + ((mod, head),))
            return None if base is None else base + rest
        return None

    def resolve(self, path, seen=()):
        """(module that defines what the crate-relative path names, whether it was found); the
        module is None for an item that the crate imports from outside."""
        n = 0
        while n < len(path) and path[: n + 1] in self.file_of:
            n += 1
        mod, rest = path[:n], path[n:]
        if not rest:
            return mod, True
        name = rest[0]
        if name in self.uses[mod] and (mod, name) not in seen:
            target = self.absolute(mod, (name,) + rest[1:], seen + ((mod, name),))
            return (None, True) if target is None else self.resolve(target, seen + ((mod, name),))
        if name in self.defined[mod]:
            return mod, True
        for use_mod, glob in self.globs[mod]:
            base = self.absolute(use_mod, glob)
            if base is not None and (mod, glob) not in seen:
                found, exact = self.resolve(base + rest, seen + ((mod, glob),))
                if exact:
                    return found, True
        return mod, False

    def edges(self):
        """{file: {file it imports from: the first path that does}}."""
        out = {f: {} for f in set(self.file_of.values())}
        for file, mod, path, kind in self.refs:
            target_path = self.absolute(mod, path)
            if target_path is None or (kind == "use" and target_path in self.file_of):
                continue
            target, _ = self.resolve(target_path)
            if target is not None and self.file_of[target] != file:
                out[file].setdefault(self.file_of[target], "::".join(path))
        return out


def use_tree(toks):
    """[(path, name it is imported as)] of the tokens of a use declaration; `*` names a glob."""
    out = []

    def walk(prefix, i):
        path = list(prefix)
        while i < len(toks):
            t = toks[i]
            if t == "{":
                i += 1
                while toks[i] != "}":
                    i = walk(path, i)
                    i += toks[i] == ","
                return i + 1
            if t in (",", "}"):
                return i
            if t == "as":
                out[-1] = (out[-1][0], toks[i + 1])
                i += 1
            elif t == "*":
                out.append((tuple(path), "*"))
            elif t == "self" and toks[i + 1 : i + 2] != ["::"]:
                out.append((tuple(path), path[-1]))
            elif t != "::":
                path.append(t)
                if toks[i + 1 : i + 2] != ["::"]:
                    out.append((tuple(path), t))
            i += 1
        return i

    walk([], int(toks[:1] == ["::"]))
    return out


def strongly_connected(graph):
    """Tarjan's algorithm: the components of the graph {node: successors}, iteratively."""
    index, low, stack, on_stack, comps = {}, {}, [], set(), []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, succ = work[-1]
            nxt = next(succ, None)
            if nxt is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == node:
                            break
                    comps.append(comp)
            elif nxt not in index:
                index[nxt] = low[nxt] = len(index)
                stack.append(nxt)
                on_stack.add(nxt)
                work.append((nxt, iter(sorted(graph[nxt]))))
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
    return comps


def crate_cycles(files):
    """The cycles of one crate given as {module path: text}: sorted lists of module paths, and
    the graph's edges."""
    graph = Crate(files).edges()
    return sorted(sorted(c) for c in strongly_connected(graph) if len(c) > 1), graph


def load(crate_dir):
    src = Path(crate_dir) / "src"
    files = {}
    for f in sorted(src.rglob("*.rs")):
        if "bin" not in f.relative_to(src).parts[:1]:
            files[module_path(src, f)] = f
    return files


def main(args):
    if args == ["--self-test"]:
        return self_test()
    root = Path(__file__).resolve().parent.parent
    dirs = [Path(a) for a in args] or sorted(p.parent for p in (root / "crates").glob("*/src"))
    found = 0
    for d in dirs:
        paths = load(d)
        cycles, graph = crate_cycles({m: p.read_text() for m, p in paths.items()})
        for cycle in cycles:
            found += 1
            print(f"{d.name}: import cycle between (each file, then what it imports in the cycle)")
            for m in cycle:
                shown = paths[m].resolve()
                shown = shown.relative_to(root) if shown.is_relative_to(root) else shown
                imports = [f"{paths[t].relative_to(d / 'src')} ({graph[m][t]})"
                           for t in sorted(graph[m]) if t in cycle]
                print(f"    {shown}: {', '.join(imports)}")
    if found:
        print(f"{found} import cycle(s)")
        return 1
    print(f"no import cycles in {len(dirs)} crates")
    return 0


def self_test():
    def cycles(**files):
        mods = {tuple(k.split("__")) if k != "lib" else (): v for k, v in files.items()}
        return crate_cycles(mods)[0]

    cases = [
        # A parent re-exporting its child while the child names an item defined in the parent.
        (cycles(lib="mod a; pub use a::A; pub struct R;", a="use crate::R; pub struct A;"),
         [[(), ("a",)]]),
        # The declaration alone is not an import.
        (cycles(lib="mod a; pub struct R;", a="use crate::R; pub struct A;"), []),
        # Re-exported names lead to the defining module: no cycle through lib.rs.
        (cycles(lib="mod a; mod b; pub use a::A; pub use b::B;",
                a="use crate::B; pub struct A;", b="pub struct B;"), []),
        (cycles(lib="mod a; mod b;", a="pub fn f() { crate::b::g() }",
                b="pub fn g() { super::a::f() }"), [[("a",), ("b",)]]),
        # super:: in an inline test module is the file itself; comments and strings are ignored.
        (cycles(lib="mod a; pub fn r() { a::f() }",
                a="pub fn f() {} // crate::r\n mod tests { use super::*; const S: &str = \"super::r\"; }"),
         []),
        # A child's glob of its parent, and nested directories with mod.rs.
        (cycles(lib="mod s;", s="mod p; pub use p::P; pub struct Q;",
                s__p="use super::*; pub struct P(Q);"), [[("s",), ("s", "p")]]),
        # Through a module imported by name.
        (cycles(lib="mod a; mod b;", a="use crate::b; pub fn f() { b::g() }",
                b="use super::a::{self, f as h}; pub fn g() { h() }"), [[("a",), ("b",)]]),
        (cycles(lib="mod a; mod b;", a="use crate::b; pub fn f() {}", b="pub fn g() {}"), []),
        # An item the parent imports from another crate leads out of the crate.
        (cycles(lib="mod a; use ext::X; pub use a::A;", a="use crate::X; pub struct A(X);"), []),
        (cycles(lib="mod a; pub(crate) use a::{A as B, f}; pub fn g() {}",
                a="pub struct A; pub fn f() { crate::g() }"), [[(), ("a",)]]),
    ]
    failed = [n for n, (got, want) in enumerate(cases) if got != want]
    for n in failed:
        print(f"case {n}: got {cases[n][0]}, expected {cases[n][1]}")
    print("self-test:", "failed" if failed else f"{len(cases)} cases passed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
