// emit.mjs - declarations and statements of gen-wgsl.mjs: a parsed GLSL module to WGSL text.
import { fail, Parser } from './front.mjs';
import { ExprEmitter } from './expr.mjs';
import { TEXTURES, BOOL, isInt, glslName, same, wgslType, HELPERS } from './types.mjs';

/** The names assigned (=, op=, ++, --, out arguments) anywhere below `node`. */
function assignedRoots(node, fns, set = new Set()) {
  const root = (e) => { while (e.k === 'mem' || e.k === 'idx' || e.k === 'paren') e = e.a; return e.k === 'id' ? e.name : null; };
  if (Array.isArray(node)) { for (const x of node) assignedRoots(x, fns, set); return set; }
  if (!node || typeof node !== 'object' || node.file) return set;  // tokens and locations
  if (node.k === 'assign' || node.k === 'pre' || node.k === 'post') set.add(root(node.a));
  if (node.k === 'call') {
    const f = fns.get(node.name);
    node.args.forEach((a, i) => {
      if ((f && f.params[i] && f.params[i].dir !== 'in') || (node.name === 'umulExtended' && i >= 2)) set.add(root(a));
    });
  }
  for (const [key, v] of Object.entries(node)) if (key !== 'loc' && key !== 'q' && typeof v === 'object') assignedRoots(v, fns, set);
  return set;
}

/** The comment lines directly above a declaration (no blank or directive line between). */
function leadingComments(d) {
  const cs = (d.comments || []).filter((c) => c.alone);
  const out = [];
  let line = d.loc.line;
  for (let i = cs.length - 1; i >= 0 && cs[i].file === d.loc.file && cs[i].line === line - 1; --i, --line) out.unshift(cs[i]);
  return out.map((c) => `//${c.text}`);
}

export class Translator extends ExprEmitter {
  /** opts: { kernel: whether `main` is the compute entry point, allIds: every identifier of the source }. */
  constructor(opts = {}) {
    super();
    this.opts = opts;
    this.allIds = opts.allIds;
    this.structs = new Map();
    this.fns = new Map();
    this.helpers = new Set();
    this.renamed = new Set();
    this.scopes = [new Map()];
    this.bindings = [];
    this.localSize = null;
    this.cur = null;
    this.lines = [];
  }
  global(name, entry, at) {
    if (this.scopes[0].has(name) || this.fns.has(name)) fail(at, `${name} is declared twice`);
    this.scopes[0].set(name, entry);
  }
  emit(line) { this.lines.push(line); }

  module(decls) {
    let prev = null;
    for (const d of decls) {
      const start = this.lines.length;
      if (d.k === 'empty') continue;
      if (d.k === 'struct') this.struct(d);
      else if (d.k === 'block') this.block(d);
      else if (d.k === 'local_size') this.localSize = d;
      else if (d.k === 'global') this.globalDecl(d);
      else if (d.k === 'fn') this.func(d);
      if (this.lines.length > start && d.loc) {
        const cs = leadingComments(d);
        const blank = start > 0 && (d.k !== 'global' || prev !== 'global' || cs.length > 0);
        this.lines.splice(start, 0, ...(blank ? [''] : []), ...cs);
      }
      prev = d.k;
    }
    if (this.opts.kernel && !this.fns.has('main')) fail(null, 'the kernel has no main');
    const helpers = [...this.helpers].sort().map((h) => HELPERS[h]);
    return [...(helpers.length ? [helpers.join('\n\n'), ''] : []), ...this.lines].join('\n') + '\n';
  }

  struct(d) {
    const ms = d.members.map((m) => ({ name: m.name, t: this.type(m.type, m.arr, m.loc), loc: m.loc }));
    for (const m of ms) if (m.t.arr && m.t.sizeText === undefined) fail(m.loc, 'runtime-sized array in a struct');
    this.structs.set(d.name, ms);
    this.emit(`struct ${this.nm(d.name, d.loc)} {`);
    for (const m of ms) this.emit(`  ${this.nm(m.name, m.loc)}: ${wgslType(m.t)},`);
    this.emit('}');
  }
  /** Host-shareable types only (no bool): the buffer layouts must equal std140/std430's. */
  checkShareable(t, at, uniform) {
    if (t.b === 'bool') fail(at, 'bool in a buffer (not host-shareable in WGSL)');
    if (uniform && !t.b) fail(at, `${glslName(t)} in a uniform block (only scalars and vectors keep std140 offsets)`);
    if (t.arr) this.checkShareable(t.arr, at, uniform);
    if (t.st) for (const m of this.structs.get(t.st)) this.checkShareable(m.t, m.loc, uniform);
  }
  /** Uniform blocks (std140 or push_constant) and buffers (std430). */
  block(d) {
    const lay = d.q.layout, at = d.loc;
    const push = !!lay.push_constant, uniform = d.q.set.has('uniform');
    if (uniform && !push && !lay.std140) fail(at, `uniform block ${d.name} without std140`);
    if (!uniform && !lay.std430) fail(at, `buffer ${d.name} without std430`);
    if (!push && lay.binding === undefined) fail(at, `${d.name} without a binding`);
    const ms = d.members.map((m) => ({ name: m.name, t: this.type(m.type, m.arr, m.loc), loc: m.loc }));
    ms.forEach((m, i) => {
      this.checkShareable(m.t, m.loc, uniform);
      if (m.t.arr && m.t.sizeText === undefined && (uniform || i !== ms.length - 1)) fail(m.loc, 'runtime array not last in a buffer');
    });
    const space = uniform ? 'uniform' : d.q.set.has('readonly') ? 'storage, read' : 'storage, read_write';
    const mutable = !uniform && !d.q.set.has('readonly');
    const group = push ? 1 : 0, binding = push ? 0 : +lay.binding;
    const attr = `@group(${group}) @binding(${binding})`;
    const kind = mutable ? 'storage-w' : 'ro';
    if (!d.inst && ms.length === 1 && ms[0].t.arr && ms[0].t.sizeText === undefined) {
      const name = this.nm(ms[0].name, ms[0].loc);
      this.global(ms[0].name, { kind, c: name, t: ms[0].t }, at);
      this.emit(`${attr} var<${space}> ${name}: ${wgslType(ms[0].t)};`);
      this.bindings.push({ group, binding, name, what: `var<${space}> ${wgslType(ms[0].t)} (GLSL ${d.name})` });
      return;
    }
    this.structs.set(d.name, ms);
    this.emit(`struct ${this.nm(d.name, at)} {`);
    for (const m of ms) this.emit(`  ${this.nm(m.name, m.loc)}: ${wgslType(m.t)},`);
    this.emit('}');
    const vname = d.inst ? this.nm(d.inst, at) : d.name[0].toLowerCase() + d.name.slice(1);
    if (!d.inst && this.allIds?.has(vname)) fail(at, `the variable ${vname} of block ${d.name} clashes with an existing name`);
    if (d.inst) this.global(d.inst, { kind, c: vname, t: { st: d.name } }, at);
    else for (const m of ms) this.global(m.name, { kind, c: `${vname}.${this.nm(m.name, m.loc)}`, t: m.t }, m.loc);
    this.emit(`${attr} var<${space}> ${vname}: ${d.name};`);
    this.bindings.push({ group, binding, name: vname, what: `var<${space}> ${d.name}${push ? ' (GLSL push_constant)' : ''}` });
  }
  globalDecl(d) {
    const q = d.q.set;
    for (const v of d.vars) {
      const t = this.type(d.type, v.arr, v.loc);
      const name = this.nm(v.name, v.loc);
      if (t.tex) {
        if (!q.has('uniform') || d.q.layout.binding === undefined) fail(v.loc, `sampler ${v.name} without a binding`);
        const binding = +d.q.layout.binding;
        this.global(v.name, { kind: 'tex', c: name, t }, v.loc);
        this.emit(`@group(0) @binding(${binding}) var ${name}: ${TEXTURES[t.tex][0]};`);
        this.bindings.push({ group: 0, binding, name, what: `${TEXTURES[t.tex][0]} (GLSL ${t.tex})` });
      } else if (q.has('const')) {
        if (!v.init) fail(v.loc, `const ${v.name} without a value`);
        const init = this.implicit(this.ex(v.init), t, v.loc);
        this.global(v.name, { kind: 'const', c: name, t }, v.loc);
        this.emit(`const ${name}: ${wgslType(t)} = ${init.c};`);
      } else if (q.has('uniform') || q.has('buffer') || q.has('in') || q.has('out')) {
        fail(v.loc, `unsupported global ${v.name}`);
      } else {
        if (v.init) fail(v.loc, `initialised global variable ${v.name}`);
        this.global(v.name, { kind: 'private', c: name, t }, v.loc);
        this.emit(`var<private> ${name}: ${wgslType(t)};`);
      }
    }
  }

  func(d) {
    if (this.fns.has(d.name)) fail(d.loc, `${d.name} is defined twice (overloads are not supported)`);
    const main = d.name === 'main';
    if (main && !this.opts.kernel) fail(d.loc, 'main outside a kernel');
    const ret = this.type(d.ret, undefined, d.loc);
    const params = d.params.map((p) => ({ name: p.name, dir: p.dir, t: this.type(p.type, p.arr, p.loc), loc: p.loc }));
    const assigned = assignedRoots(d.body, this.fns);
    this.cur = { name: d.name, ret, main, pureFn: true, calls: new Set() };
    const scope = new Map(), sig = [], prologue = [];
    for (const p of params) {
      const name = this.nm(p.name, p.loc);
      if (p.t.tex) fail(p.loc, 'sampler parameters are not supported');
      if (p.dir !== 'in') {
        sig.push(`${name}: ptr<function, ${wgslType(p.t)}>`);
        scope.set(p.name, { kind: 'ptr', c: name, t: p.t });
      } else if (assigned.has(p.name)) {  // WGSL parameters are immutable: a local copy
        if (this.allIds?.has(`${name}_in`)) fail(p.loc, `parameter copy ${name}_in clashes with an existing name`);
        sig.push(`${name}_in: ${wgslType(p.t)}`);
        prologue.push(`  var ${name}: ${wgslType(p.t)} = ${name}_in;`);
        scope.set(p.name, { kind: 'var', c: name, t: p.t });
      } else {
        sig.push(`${name}: ${wgslType(p.t)}`);
        scope.set(p.name, { kind: 'val', c: name, t: p.t });
      }
    }
    let head;
    if (main) {
      if (params.length || !ret.void) fail(d.loc, 'main takes nothing and returns void');
      const ls = this.localSize?.layout || {};
      if (!ls.local_size_x) fail(d.loc, 'main without layout(local_size_x = N) in');
      const size = [ls.local_size_x, ls.local_size_y, ls.local_size_z].filter((x) => x !== undefined).join(', ');
      head = `@compute @workgroup_size(${size})\nfn main(@builtin(global_invocation_id) gl_GlobalInvocationID: vec3<u32>) {`;
      scope.set('gl_GlobalInvocationID', { kind: 'builtin', c: 'gl_GlobalInvocationID', t: { b: 'uint', n: 3 } });
    } else head = `fn ${this.nm(d.name, d.loc)}(${sig.join(', ')})${ret.void ? '' : ` -> ${wgslType(ret)}`} {`;
    this.fns.set(d.name, { params, ret, pureFn: true });
    this.scopes.push(scope);
    const body = [];
    const saved = this.lines;
    this.lines = body;
    for (const s of d.body.list) this.stmt(s, 1);
    this.lines = saved;
    this.scopes.pop();
    this.fns.get(d.name).pureFn = this.cur.pureFn && !this.cur.writesGlobal;
    this.emit(head);
    for (const l of prologue) this.emit(l);
    for (const l of body) this.emit(l);
    this.emit('}');
    this.cur = null;
  }

  // ---- Statements ----
  stmt(s, ind) {
    const pad = '  '.repeat(ind);
    switch (s.k) {
      case 'block':
        this.emit(`${pad}{`);
        this.body(s, ind + 1);
        this.emit(`${pad}}`);
        return;
      case 'decl': return this.decl(s, ind);
      case 'expr': this.emit(`${pad}${this.simple(s.e)};`); return;
      case 'if': return this.ifStmt(s, ind, pad);
      case 'for': return this.forStmt(s, ind, pad);
      case 'while': {
        const c = this.ex(s.c);
        if (!same(c.t, BOOL)) fail(s.loc, 'while condition is not a bool');
        this.emit(`${pad}while (${c.c}) {`);
        this.body(s.body, ind + 1);
        this.emit(`${pad}}`);
        return;
      }
      case 'break': case 'continue': this.emit(`${pad}${s.k};`); return;
      case 'return': {
        const ret = this.cur.ret;
        if (!s.e) { if (!ret.void) fail(s.loc, 'return without a value'); this.emit(`${pad}return;`); return; }
        if (ret.void) fail(s.loc, 'return with a value from a void function');
        this.emit(`${pad}return ${this.implicit(this.ex(s.e), ret, s.loc).c};`);
        return;
      }
      default: fail(s.loc, `unsupported statement ${s.k}`);
    }
  }
  /** A statement as a body in braces, in its own scope. */
  body(s, ind) {
    this.scopes.push(new Map());
    if (s.k === 'block') for (const x of s.list) this.stmt(x, ind);
    else this.stmt(s, ind);
    this.scopes.pop();
  }
  ifStmt(s, ind, pad, prefix = '') {
    const c = this.ex(s.c);
    if (!same(c.t, BOOL)) fail(s.loc, 'if condition is not a bool');
    this.emit(`${pad}${prefix}if (${c.c}) {`);
    this.body(s.a, ind + 1);
    if (s.b && s.b.k === 'if') {
      this.ifStmt(s.b, ind, pad, '} else ');
      return;
    }
    if (s.b) {
      this.emit(`${pad}} else {`);
      this.body(s.b, ind + 1);
    }
    this.emit(`${pad}}`);
  }
  forStmt(s, ind, pad) {
    this.scopes.push(new Map());
    let init = '';
    if (s.init && s.init.k === 'decl') {
      const lines = this.lines;
      this.lines = [];
      this.decl(s.init, 0);
      if (this.lines.length !== 1) fail(s.loc, 'for initialiser declaring more than one variable');
      init = this.lines[0].replace(/;$/, '');
      this.lines = lines;
    } else if (s.init) init = this.simple(s.init.e);
    const c = s.c ? this.ex(s.c) : null;
    if (c && !same(c.t, BOOL)) fail(s.loc, 'for condition is not a bool');
    const u = s.u ? this.simple(s.u) : '';
    this.emit(`${pad}for (${init}; ${c ? c.c : ''}; ${u}) {`);
    this.body(s.body, ind + 1);
    this.emit(`${pad}}`);
    this.scopes.pop();
  }
  decl(s, ind) {
    const pad = '  '.repeat(ind);
    const isConst = s.q.set.has('const');
    for (const v of s.vars) {
      const t = this.type(s.type, v.arr, v.loc);
      if (t.tex || t.void) fail(v.loc, `local ${glslName(t)}`);
      if (t.arr && t.sizeText === undefined) fail(v.loc, 'unsized local array');
      const name = this.nm(v.name, v.loc);
      let after = null, init = null;
      if (v.init && (v.init.k === 'post') && v.init.a.k === 'id') {  // `int b = k++;`: b = k, then k++
        init = this.implicit(this.ex(v.init.a), t, v.loc);
        after = this.simple(v.init);
      } else if (v.init) init = this.implicit(this.ex(v.init), t, v.loc);
      if (isConst && !init) fail(v.loc, `const ${v.name} without a value`);
      const top = this.scopes[this.scopes.length - 1];
      if (top.has(v.name)) fail(v.loc, `${v.name} is declared twice`);
      top.set(v.name, { kind: isConst ? 'const' : 'var', c: name, t });
      this.emit(`${pad}${isConst ? 'const' : 'var'} ${name}: ${wgslType(t)}${init ? ` = ${init.c}` : ''};`);
      if (after) this.emit(`${pad}${after};`);
    }
  }
  /** An expression statement's text (no ';'): an assignment, increment or call. */
  simple(e) {
    if (e.k === 'paren') return this.simple(e.a);
    if (e.k === 'pre' || e.k === 'post') {
      const lv = this.lvalue(e.a);
      if (!isInt(lv.t) || lv.t.n !== 1) fail(e.loc, `${e.op} on ${glslName(lv.t)}`);
      return `${lv.c}${e.op}`;
    }
    if (e.k === 'assign') {
      const lv = this.lvalue(e.a);
      let r = this.ex(e.b);
      if (e.op === '=') r = this.implicit(r, lv.t, e.loc);
      else {
        const op = e.op.slice(0, -1);
        const check = this.binary({ k: 'bin', op, a: e.a, b: e.b, loc: e.loc });  // types as a op b
        if (!same(check.t, lv.t)) fail(e.loc, `${e.op} changes the type of ${glslName(lv.t)}`);
        if (op === '<<' || op === '>>') r = r.abs ? { ...r, c: `${r.c}u` } : r.t.b === 'uint' ? r : this.toBase(r, 'uint', e.loc, true);
        else if (r.t.b !== lv.t.b) r = this.toBase(r, lv.t.b, e.loc);
      }
      return `${lv.c} ${e.op} ${r.c}`;
    }
    if (e.k === 'call') {
      const r = this.ex(e);
      if (!r.call) fail(e.loc, `the value of ${e.name}() is unused`);
      return r.c;
    }
    fail(e.loc, 'expression statement without an effect');
  }
  lvalue(e) {
    const r = this.ex(e);
    const s = r.root;
    if (!s || !['var', 'ptr', 'private', 'storage-w'].includes(s.kind)) fail(e.loc, 'assignment to a read-only value');
    if (r.swizzle > 1) fail(e.loc, 'assignment to a multi-component swizzle (not allowed in WGSL)');
    if (s.kind === 'private' || s.kind === 'storage-w') this.cur.writesGlobal = true;
    return r;
  }
}

/** The WGSL text of a preprocessed token list. */
export function translateTokens(toks, opts) {
  const decls = new Parser(toks).top();
  const tr = new Translator({ ...opts, allIds: new Set(toks.filter((t) => t.t === 'id').map((t) => t.v)) });
  const code = tr.module(decls);
  return { code, bindings: tr.bindings, renamed: [...tr.renamed].sort(), functions: [...tr.fns.keys()] };
}
