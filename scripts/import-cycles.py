#!/usr/bin/env python3
"""Import cycles between the files of each crate under crates/ (docs/design.md, "The crates and the kernels").
File A depends on file B when A names an item that B defines: through any path (crate::.., super::.., a child
module's name), and through a re-export, which is followed to the file that defines the item. Module
declarations and re-exports are not uses, nor are the unit tests at the end of a file. Prints each cycle with
its edges and exits 1; exits 0 when there is none."""
import os, re, sys
root = sys.argv[1] if len(sys.argv) > 1 else '.'
def modules(src):
    mods = {}
    for d, _, fs in os.walk(src):
        for f in fs:
            if not f.endswith('.rs'): continue
            p = os.path.join(d, f); rel = os.path.relpath(p, src)[:-3].split(os.sep)
            if rel[:1] == ['bin']: continue
            if rel[-1] in ('lib', 'main', 'mod'): rel = rel[:-1]
            mods[tuple(rel)] = p
    return mods
def strip(text):
    text = re.sub(r'//[^\n]*', '', text)
    i = text.find('#[cfg(test)]\nmod tests')
    return text if i < 0 else text[:i]
DEF = re.compile(r'^(?:pub(?:\([a-z]+\))? )?(?:async |const |unsafe )*(?:struct|enum|fn|const|static|trait|type|union) ([A-Za-z_][A-Za-z0-9_]*)', re.M)
MACRO = re.compile(r'^macro_rules! ([a-z_0-9]+)', re.M)
bad = False
for c in sorted(os.listdir(os.path.join(root, 'crates'))):
    src = os.path.join(root, 'crates', c, 'src')
    if not os.path.isdir(src): continue
    mods = modules(src)
    texts = {m: strip(open(p).read()) for m, p in mods.items()}
    defs = {}
    for m, t in texts.items():
        for name in DEF.findall(t) + MACRO.findall(t):
            defs.setdefault(name, set()).add(m)
    def resolve(m, path):
        """The module a path names, and the item it ends on (if any)."""
        for k in range(len(path), -1, -1):
            if tuple(path[:k]) in mods:
                return tuple(path[:k]), (path[k] if k < len(path) else None)
        return None, None
    edges = {m: set() for m in mods}
    for m, t in texts.items():
        body = re.sub(r'^\s*pub(?:\([a-z]+\))? use [^;]*;', '', t, flags=re.M)  # re-exports are not uses
        body = re.sub(r'^\s*(?:pub(?:\([a-z]+\))? )?mod [a-z_0-9]+;', '', body, flags=re.M)
        paths = []
        # use trees: expand one level of braces
        for base, inner in re.findall(r'\b((?:crate|super|self)(?:::super)*(?:::[a-z_][a-z0-9_]*)*)::\{([^}]*)\}', body):
            for item in inner.split(','):
                item = item.strip().split(' as ')[0].strip()
                if item: paths.append(base + '::' + item)
        paths += re.findall(r'\b((?:crate|super)(?:::[A-Za-z_][A-Za-z0-9_]*)+)', body)
        children = [k[-1] for k in mods if k[:-1] == m and len(k) == len(m) + 1]
        for ch in children:
            for rest in re.findall(r'(?<![:\w])%s((?:::[A-Za-z_][A-Za-z0-9_]*)+)' % ch, body):
                paths.append('self::' + ch + rest)
        for p in paths:
            parts = p.split('::')
            if parts[0] == 'crate': base, parts = (), parts[1:]
            elif parts[0] == 'self': base, parts = m, parts[1:]
            else:
                n = 0
                while parts and parts[0] == 'super': n += 1; parts = parts[1:]
                base = m[:len(m) - n]
            target, item = resolve(m, list(base) + parts)
            if target is None: continue
            if item and item not in DEF.findall(texts[target]):
                if item not in defs:
                    continue  # a re-export of another crate's item
                # a re-export: follow it to the file that defines the item
                owners = defs[item]
                target = next(iter(owners)) if len(owners) == 1 else target
            if target != m: edges[m].add(target)
    idx, low, st, on, out, n = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(10000)
    def sc(v):
        idx[v] = low[v] = n[0]; n[0] += 1; st.append(v); on.add(v)
        for w in edges[v]:
            if w not in idx: sc(w); low[v] = min(low[v], low[w])
            elif w in on: low[v] = min(low[v], idx[w])
        if low[v] == idx[v]:
            comp = []
            while True:
                w = st.pop(); on.discard(w); comp.append(w)
                if w == v: break
            if len(comp) > 1: out.append(comp)
    for v in edges:
        if v not in idx: sc(v)
    for comp in out:
        bad = True
        names = lambda k: '/'.join(k) or 'lib.rs'
        print('crates/%s: %s' % (c, ', '.join(names(k) for k in sorted(comp))))
        for a in sorted(comp):
            print('   ', names(a), '->', ', '.join(names(b) for b in sorted(edges[a]) if b in comp))
sys.exit(1 if bad else 0)
