#!/usr/bin/env python3
"""Lists cycles in a Rust crate's file-level import graph; exits 1 if any.

    cd crates/mpm/src && python3 ../../../scripts/import_cycles.py

Reads every .rs file below the current folder (items marked
`#[cfg(test)]`, test modules or not, and comments left out), resolves each `crate::` and `super::` path to the file that holds
the module it names, and prints the strongly connected components with more
than one file. `cycles: []` means the files import each other without a
cycle; the same is then done for the top-level modules (a folder counts as
one module). A text scan, not a compiler: a path spelled through a
re-export counts against the file that re-exports it, and a parent
module's `pub use` of its own children is not counted as an import.
"""
import os,re,sys


def without_test_items(text):
    """`text` without each `#[cfg(test)]` item: up to its `;`, or its
    braces' match (braces in strings and format strings come in pairs)."""
    out, at = [], 0
    while (i := text.find("#[cfg(test)]", at)) >= 0:
        out.append(text[at:i])
        j = i + len("#[cfg(test)]")
        semicolon, brace = text.find(";", j), text.find("{", j)
        if brace < 0 or 0 <= semicolon < brace:
            at = semicolon + 1
            continue
        depth = 0
        for k in range(brace, len(text)):
            depth += {"{": 1, "}": -1}.get(text[k], 0)
            if depth == 0:
                break
        at = k + 1
    return "".join(out) + text[at:]


files={}
for root,_,fs in os.walk('.'):
    for f in fs:
        if f.endswith('.rs'):
            p=os.path.join(root,f)[2:]
            s=without_test_items(open(p).read())
            s='\n'.join(l for l in s.splitlines() if not l.strip().startswith('//'))
            files[p]=s
def modpath(p):
    parts=p[:-3].split('/')
    if parts[-1] in('mod','lib'): parts=parts[:-1]
    return parts
mods={tuple(modpath(p)):p for p in files}
def resolve(parts):
    for k in range(len(parts),0,-1):
        if tuple(parts[:k]) in mods: return mods[tuple(parts[:k])]
edges={}
for p,s in files.items():
    me=modpath(p); deps=set()
    for m in re.finditer(r'\b(crate|super)::((?:\w+::)*)(\{[^}]*\}|\w+)', s):
        path=[x for x in m.group(2).split('::') if x]
        parts=path if m.group(1)=='crate' else me[:-1]+path
        last=m.group(3)
        items=[last] if not last.startswith('{') else [x.strip().split('::')[0] for x in last[1:-1].split(',') if x.strip()]
        for it in items:
            t=resolve(parts+[it]) or resolve(parts)
            if t and t!=p: deps.add(t)
    # `mod x;` declarations are containment, not imports
    edges[p]=deps
index={};low={};st=[];on=set();res=[];i=[0]
sys.setrecursionlimit(10000)
def sc(v):
    index[v]=low[v]=i[0];i[0]+=1;st.append(v);on.add(v)
    for w in edges[v]:
        if w not in index: sc(w); low[v]=min(low[v],low[w])
        elif w in on: low[v]=min(low[v],index[w])
    if low[v]==index[v]:
        comp=[]
        while True:
            w=st.pop();on.discard(w);comp.append(w)
            if w==v:break
        if len(comp)>1: res.append(comp)
for v in edges:
    if v not in index: sc(v)
print("cycles:", res)
file_cycles = bool(res)

# The same for top-level modules: `grid/basis.rs` belongs to `grid`.
def top(p):
    return p.split("/")[0].removesuffix(".rs")


module_edges = {}
for p, ds in edges.items():
    module_edges.setdefault(top(p), set())
    module_edges[top(p)] |= {top(d) for d in ds if top(d) != top(p)}
edges = {m: {f"{d}" for d in ds} for m, ds in module_edges.items()}
for d in {d for ds in edges.values() for d in ds}:
    edges.setdefault(d, set())
index = {}
low = {}
st = []
on = set()
res = []
i = [0]
for v in edges:
    if v not in index:
        sc(v)
print("module cycles:", res)
sys.exit(1 if file_cycles or res else 0)
