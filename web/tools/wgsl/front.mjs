// front.mjs - the front end of gen-wgsl.mjs: preprocessor, tokenizer and parser for the GLSL subset
// of gpu/glsl and gpu/vulkan/shaders. Anything outside that subset throws with file:line.

export class WgslError extends Error {}

/** Throws a WgslError naming where (a token or node with file and line) and what. */
export function fail(at, what) {
  const where = at && at.file ? `${at.file}:${at.line}: ` : '';
  throw new WgslError(`${where}${what}`);
}

const OPS = ['<<=', '>>=', '++', '--', '&&', '||', '^^', '==', '!=', '<=', '>=', '+=', '-=', '*=', '/=', '%=',
  '&=', '|=', '^=', '<<', '>>', ...'+-*/%<>=!~&|^?:;,.()[]{}'];
const NUM = /^(0[xX][0-9a-fA-F]+[uU]?|(\d+\.\d*|\.\d+|\d+)([eE][+-]?\d+)?[fFuU]?)/;
const ID = /^[A-Za-z_][A-Za-z0-9_]*/;

/** The tokens of one line; a `//` comment is returned apart. */
function tokenizeLine(text, file, line) {
  const toks = [];
  let i = 0, comment = null;
  while (i < text.length) {
    const rest = text.slice(i);
    const ws = /^\s+/.exec(rest);
    if (ws) { i += ws[0].length; continue; }
    if (rest.startsWith('//')) { comment = rest.slice(2); break; }
    if (rest.startsWith('/*')) fail({ file, line }, 'block comments are not supported');
    let m = NUM.exec(rest);
    if (m && !/^[A-Za-z_]/.test(rest)) { toks.push({ t: 'num', v: m[0], file, line }); i += m[0].length; continue; }
    m = ID.exec(rest);
    if (m) { toks.push({ t: 'id', v: m[0], file, line }); i += m[0].length; continue; }
    const op = OPS.find((o) => rest.startsWith(o));
    if (!op) fail({ file, line }, `unexpected character '${rest[0]}'`);
    toks.push({ t: 'op', v: op, file, line });
    i += op.length;
  }
  return { toks, comment };
}

/** Object-like macro expansion; the expansion carries the use's location. */
function expand(toks, macros, hide = new Set()) {
  const out = [];
  for (const tk of toks) {
    if (tk.t === 'id' && macros.has(tk.v) && !hide.has(tk.v)) {
      const body = macros.get(tk.v).map((b) => ({ ...b, file: tk.file, line: tk.line }));
      out.push(...expand(body, macros, new Set([...hide, tk.v])));
    } else out.push(tk);
  }
  return out;
}

/** `defined(X)`, `defined X`, `!defined(X)` and nothing else. */
function evalIf(expr, macros, at) {
  const m = /^(!?)\s*defined\s*(?:\(\s*([A-Za-z_]\w*)\s*\)|\s([A-Za-z_]\w*))\s*$/.exec(expr.trim());
  if (!m) fail(at, `unsupported #if expression '${expr.trim()}'`);
  const d = macros.has(m[2] || m[3]);
  return m[1] ? !d : d;
}

/**
 * Preprocesses `text` (named `file`) into tokens, macros expanded, each with file and line; comment
 * lines are attached to the next token as `comments`. ctx: { macros: Map, include(name, at) ->
 * { file, text } }.
 */
export function preprocess(file, text, ctx, out = { toks: [], pending: [] }) {
  const stack = [];
  const active = () => stack.every((s) => s.on);
  const lines = text.split('\n');
  for (let n = 0; n < lines.length; ++n) {
    const raw = lines[n], line = n + 1, at = { file, line };
    if (/\\\s*$/.test(raw)) fail(at, 'line continuations are not supported');
    const d = /^\s*#\s*(\w+)\s*(.*)$/.exec(raw);
    if (d) {
      const [, dir, restRaw] = d;
      const rest = restRaw.replace(/\/\/.*$/, '').trim();
      if (dir === 'ifdef' || dir === 'ifndef') {
        const on = ctx.macros.has(rest) === (dir === 'ifdef');
        stack.push({ on, taken: on, at });
      } else if (dir === 'if') {
        const on = evalIf(rest, ctx.macros, at);
        stack.push({ on, taken: on, at });
      } else if (dir === 'elif' || dir === 'else') {
        const s = stack[stack.length - 1];
        if (!s) fail(at, `#${dir} without #if`);
        const on = !s.taken && (dir === 'else' || evalIf(rest, ctx.macros, at));
        s.on = on;
        s.taken = s.taken || on;
      } else if (dir === 'endif') {
        if (!stack.pop()) fail(at, '#endif without #if');
      } else if (!active()) {
        continue;
      } else if (dir === 'version' || dir === 'extension') {
        continue;  // WGSL has neither
      } else if (dir === 'define') {
        const m = /^([A-Za-z_]\w*)(\(?)\s*(.*)$/.exec(rest);
        if (!m) fail(at, `malformed #define '${rest}'`);
        if (m[2]) fail(at, `function-like macro ${m[1]} is not supported`);
        ctx.macros.set(m[1], tokenizeLine(m[3], file, line).toks);
      } else if (dir === 'undef') {
        ctx.macros.delete(rest);
      } else if (dir === 'include') {
        const m = /^"([^"]+)"$/.exec(rest);
        if (!m) fail(at, `unsupported #include ${rest}`);
        const inc = ctx.include(m[1], at);
        preprocess(inc.file, inc.text, ctx, out);
      } else if (dir === 'error') {
        fail(at, `#error ${rest}`);
      } else fail(at, `unsupported directive #${dir}`);
      continue;
    }
    if (!active()) continue;
    const { toks, comment } = tokenizeLine(raw, file, line);
    const ex = expand(toks, ctx.macros);
    if (ex.length) {
      ex[0].comments = out.pending;
      out.pending = [];
      out.toks.push(...ex);
    }
    if (comment !== null) out.pending.push({ text: comment, file, line, alone: toks.length === 0 });
  }
  if (stack.length) fail(stack[stack.length - 1].at, 'unterminated #if');
  return out;
}

// ---- Parser --------------------------------------------------------------------------------------
const BASIC = new Set(['void', 'float', 'int', 'uint', 'bool', 'vec2', 'vec3', 'vec4', 'ivec2', 'ivec3', 'ivec4',
  'uvec2', 'uvec3', 'uvec4', 'bvec2', 'bvec3', 'bvec4', 'mat3', 'sampler2DArray', 'usampler2DArray', 'isampler2DArray',
  'usampler3D', 'isampler3D', 'sampler3D']);
const QUALS = new Set(['const', 'precise', 'highp', 'mediump', 'lowp', 'in', 'out', 'inout', 'uniform', 'readonly',
  'writeonly', 'buffer', 'layout']);
const UNSUPPORTED = new Set(['do', 'switch', 'discard', 'shared', 'coherent', 'volatile', 'restrict', 'flat',
  'smooth', 'centroid', 'invariant', 'subroutine', 'mat2', 'mat4', 'double', 'dvec2', 'dvec3', 'dvec4']);
const BINARY = [['||'], ['^^'], ['&&'], ['|'], ['^'], ['&'], ['==', '!='], ['<', '>', '<=', '>='], ['<<', '>>'],
  ['+', '-'], ['*', '/', '%']];
const ASSIGN = new Set(['=', '+=', '-=', '*=', '/=', '%=', '&=', '|=', '^=', '<<=', '>>=']);

export class Parser {
  constructor(toks) { this.toks = toks; this.i = 0; this.structs = new Set(); }
  peek(o = 0) { return this.toks[this.i + o]; }
  at() { return this.peek() || this.toks[this.toks.length - 1]; }
  next() {
    const t = this.toks[this.i++];
    if (!t) fail(this.toks[this.toks.length - 1], 'unexpected end of input');
    return t;
  }
  is(v, o = 0) { const t = this.peek(o); return !!t && t.v === v && t.t !== 'num'; }
  eat(v) { if (this.is(v)) { return this.next(); } return null; }
  expect(v) {
    const t = this.next();
    if (t.v !== v) fail(t, `expected '${v}', found '${t.v}'`);
    return t;
  }
  ident() {
    const t = this.next();
    if (t.t !== 'id') fail(t, `expected a name, found '${t.v}'`);
    if (UNSUPPORTED.has(t.v)) fail(t, `'${t.v}' is not supported`);
    return t.v;
  }
  isType(o = 0) { const t = this.peek(o); return !!t && t.t === 'id' && (BASIC.has(t.v) || this.structs.has(t.v)); }

  /** Qualifiers (layout's arguments as a map) before a declaration. */
  qualifiers() {
    const q = { set: new Set(), layout: {} };
    while (this.peek() && this.peek().t === 'id' && (QUALS.has(this.peek().v) || UNSUPPORTED.has(this.peek().v))) {
      const t = this.next();
      if (UNSUPPORTED.has(t.v)) fail(t, `'${t.v}' is not supported`);
      if (t.v === 'layout') {
        this.expect('(');
        do {
          const k = this.ident();
          q.layout[k] = this.eat('=') ? this.next().v : true;
        } while (this.eat(','));
        this.expect(')');
      } else q.set.add(t.v);
    }
    return q;
  }
  typeName() {
    const t = this.next();
    if (t.t !== 'id' || !(BASIC.has(t.v) || this.structs.has(t.v))) fail(t, `unknown type '${t.v}'`);
    return { name: t.v, loc: t };
  }
  /** `[N]` or `[]` after a name: the size expression, null for a runtime array, undefined for none. */
  arraySuffix() {
    if (!this.eat('[')) return undefined;
    if (this.eat(']')) return null;
    const e = this.expr();
    this.expect(']');
    return e;
  }
  members() {
    const list = [];
    this.expect('{');
    while (!this.eat('}')) {
      const q = this.qualifiers();
      const ty = this.typeName();
      do {
        const tk = this.peek();
        list.push({ name: this.ident(), type: ty.name, arr: this.arraySuffix(), quals: q.set, loc: tk });
      } while (this.eat(','));
      this.expect(';');
    }
    return list;
  }

  top() {
    const out = [];
    while (this.peek()) out.push(this.topDecl());
    return out;
  }
  topDecl() {
    const first = this.peek(), comments = first.comments || [];
    if (this.is(';')) { this.next(); return { k: 'empty' }; }
    if (this.is('struct')) {
      this.next();
      const name = this.ident();
      this.structs.add(name);
      const members = this.members();
      this.expect(';');
      return { k: 'struct', name, members, loc: first, comments };
    }
    const q = this.qualifiers();
    if (q.set.has('in') && this.is(';')) {
      if (!q.layout.local_size_x) fail(first, 'unsupported input declaration');
      this.expect(';');
      return { k: 'local_size', layout: q.layout, loc: first };
    }
    if ((q.set.has('uniform') || q.set.has('buffer')) && this.peek().t === 'id' && !this.isType() && this.is('{', 1)) {
      const name = this.ident();
      const members = this.members();
      const inst = this.is(';') ? null : this.ident();
      this.expect(';');
      return { k: 'block', q, name, members, inst, loc: first, comments };
    }
    const ty = this.typeName();
    const nameTok = this.peek();
    const name = this.ident();
    if (this.is('(')) return this.func(q, ty, name, first, comments);
    const vars = this.declarators(ty, name, nameTok);
    return { k: 'global', q, type: ty.name, vars, loc: first, comments };
  }
  declarators(ty, name, nameTok) {
    const vars = [];
    for (;;) {
      const arr = this.arraySuffix();
      const init = this.eat('=') ? this.assignExpr() : null;
      vars.push({ name, arr, init, loc: nameTok });
      if (!this.eat(',')) break;
      nameTok = this.peek();
      name = this.ident();
    }
    this.expect(';');
    return vars;
  }
  func(q, ty, name, first, comments) {
    this.expect('(');
    const params = [];
    if (!this.eat(')')) {
      if (this.is('void') && this.is(')', 1)) { this.next(); }
      else {
        do {
          const pq = this.qualifiers();
          const pt = this.typeName();
          const tk = this.peek();
          const pn = this.ident();
          const dir = pq.set.has('inout') ? 'inout' : pq.set.has('out') ? 'out' : 'in';
          params.push({ name: pn, type: pt.name, arr: this.arraySuffix(), dir, loc: tk });
        } while (this.eat(','));
      }
      this.expect(')');
    }
    if (this.is(';')) fail(first, `function prototype ${name} is not supported`);
    if (q.set.size) fail(first, `qualifiers on function ${name}`);
    return { k: 'fn', ret: ty.name, name, params, body: this.block(), loc: first, comments };
  }

  // ---- Statements ----
  block() {
    const loc = this.expect('{');
    const list = [];
    while (!this.eat('}')) list.push(this.stmt());
    return { k: 'block', list, loc };
  }
  stmt() {
    const t = this.peek();
    if (this.is('{')) return this.block();
    if (t.t === 'id' && UNSUPPORTED.has(t.v)) fail(t, `'${t.v}' is not supported`);
    if (this.eat('if')) {
      this.expect('(');
      const c = this.expr();
      this.expect(')');
      const a = this.stmt();
      const b = this.eat('else') ? this.stmt() : null;
      return { k: 'if', c, a, b, loc: t };
    }
    if (this.eat('for')) {
      this.expect('(');
      const init = this.is(';') ? (this.next(), null) : this.simpleStmt();
      const c = this.is(';') ? null : this.expr();
      this.expect(';');
      const u = this.is(')') ? null : this.expr();
      this.expect(')');
      return { k: 'for', init, c, u, body: this.stmt(), loc: t };
    }
    if (this.eat('while')) {
      this.expect('(');
      const c = this.expr();
      this.expect(')');
      return { k: 'while', c, body: this.stmt(), loc: t };
    }
    if (this.eat('break')) { this.expect(';'); return { k: 'break', loc: t }; }
    if (this.eat('continue')) { this.expect(';'); return { k: 'continue', loc: t }; }
    if (this.eat('return')) {
      const e = this.is(';') ? null : this.expr();
      this.expect(';');
      return { k: 'return', e, loc: t };
    }
    return this.simpleStmt();
  }
  /** A declaration or an expression statement, with its ';'. */
  simpleStmt() {
    const t = this.peek();
    let o = 0;
    while (this.peek(o) && this.peek(o).t === 'id' && QUALS.has(this.peek(o).v)) ++o;
    if (this.isType(o) && this.peek(o + 1) && this.peek(o + 1).t === 'id') {
      const q = this.qualifiers();
      const ty = this.typeName();
      const nameTok = this.peek();
      return { k: 'decl', q, type: ty.name, vars: this.declarators(ty, this.ident(), nameTok), loc: t };
    }
    const e = this.expr();
    this.expect(';');
    return { k: 'expr', e, loc: t };
  }

  // ---- Expressions ----
  expr() {
    const e = this.assignExpr();
    if (this.is(',')) fail(this.peek(), 'the comma operator is not supported');
    return e;
  }
  assignExpr() {
    const a = this.condExpr();
    const t = this.peek();
    if (t && t.t === 'op' && ASSIGN.has(t.v)) {
      this.next();
      return { k: 'assign', op: t.v, a, b: this.assignExpr(), loc: t };
    }
    return a;
  }
  condExpr() {
    const c = this.binExpr(0);
    if (!this.is('?')) return c;
    const loc = this.next();
    const a = this.assignExpr();
    this.expect(':');
    const b = this.assignExpr();
    return { k: 'cond', c, a, b, loc };
  }
  binExpr(level) {
    if (level === BINARY.length) return this.unary();
    let a = this.binExpr(level + 1);
    for (;;) {
      const t = this.peek();
      if (!t || t.t !== 'op' || !BINARY[level].includes(t.v)) return a;
      this.next();
      if (t.v === '^^') fail(t, "'^^' is not supported");
      a = { k: 'bin', op: t.v, a, b: this.binExpr(level + 1), loc: t };
    }
  }
  unary() {
    const t = this.peek();
    if (t.t === 'op' && ['-', '+', '!', '~', '++', '--'].includes(t.v)) {
      this.next();
      const a = this.unary();
      return t.v === '++' || t.v === '--' ? { k: 'pre', op: t.v, a, loc: t } : { k: 'un', op: t.v, a, loc: t };
    }
    return this.postfix(this.primary());
  }
  postfix(e) {
    for (;;) {
      const t = this.peek();
      if (!t) return e;
      if (this.eat('[')) { e = { k: 'idx', a: e, i: this.expr(), loc: t }; this.expect(']'); }
      else if (this.eat('.')) {
        const name = this.ident();
        if (this.is('(')) {
          if (name !== 'length' || !this.is(')', 1)) fail(t, `method .${name}() is not supported`);
          this.next();
          this.next();
          e = { k: 'length', a: e, loc: t };
        } else e = { k: 'mem', a: e, name, loc: t };
      } else if (this.is('++') || this.is('--')) { this.next(); e = { k: 'post', op: t.v, a: e, loc: t }; }
      else return e;
    }
  }
  args() {
    const list = [];
    this.expect('(');
    if (this.eat(')')) return list;
    do list.push(this.assignExpr()); while (this.eat(','));
    this.expect(')');
    return list;
  }
  primary() {
    const t = this.next();
    if (t.t === 'num') return { k: 'lit', v: t.v, loc: t };
    if (t.v === 'true' || t.v === 'false') return { k: 'lit', v: t.v, loc: t };
    if (t.v === '(') { const e = this.expr(); this.expect(')'); return { k: 'paren', a: e, loc: t }; }
    if (t.t !== 'id') fail(t, `unexpected '${t.v}'`);
    if (UNSUPPORTED.has(t.v)) fail(t, `'${t.v}' is not supported`);
    if ((BASIC.has(t.v) || this.structs.has(t.v)) && this.is('[')) {
      this.next();
      const size = this.expr();
      this.expect(']');
      return { k: 'call', name: t.v, arr: size, args: this.args(), loc: t };
    }
    if (this.is('(')) return { k: 'call', name: t.v, args: this.args(), loc: t };
    return { k: 'id', name: t.v, loc: t };
  }
}
