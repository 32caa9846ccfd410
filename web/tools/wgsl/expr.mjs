// expr.mjs - type checking and WGSL emission of GLSL expressions for gen-wgsl.mjs. Every expression
// becomes { c: WGSL text, t: GLSL type, abs: an unsuffixed literal (WGSL abstract), pure: free of
// side effects, cls: the operator class of a binary expression (for parentheses) }.
import { fail } from './front.mjs';
import { SCALAR, TEXTURES, BOOL, INT, UINT, FLOAT, typeOf, isNum, isInt, glslName, same, wgslType, RESERVED } from './types.mjs';

const CLS = { '*': 'mul', '/': 'mul', '%': 'mul', '+': 'add', '-': 'add', '<<': 'shift', '>>': 'shift',
  '<': 'rel', '>': 'rel', '<=': 'rel', '>=': 'rel', '==': 'rel', '!=': 'rel', '&': 'bit', '|': 'bit', '^': 'bit',
  '&&': 'log', '||': 'log' };
const RANK = { int: 0, uint: 1, float: 2 };

/** Whether a binary operand needs parentheses in WGSL, whose grammar forbids mixing some classes. */
function needsParens(op, r, right) {
  const c = r.cls;
  if (!c || c === 'un') return false;
  switch (CLS[op]) {
    case 'mul': return !(c === 'mul' && !right);
    case 'add': return !(c === 'mul' || (c === 'add' && !right));
    case 'rel': return !['mul', 'add', 'shift'].includes(c);
    case 'bit': return r.op !== op;
    case 'log': return !(c === 'rel' || r.op === op);
    default: return true;
  }
}
const operand = (op, r, right) => (needsParens(op, r, right) ? `(${r.c})` : r.c);
const postfixable = (r) => (r.cls ? `(${r.c})` : r.c);
const pure = (...rs) => rs.every((r) => r.pure);
// Builtins that map one to one, component-wise; those that take several arguments get splats.
const SAME = { abs: 'abs', floor: 'floor', ceil: 'ceil', fract: 'fract', trunc: 'trunc', sqrt: 'sqrt', log: 'log',
  log2: 'log2', exp: 'exp', exp2: 'exp2', cos: 'cos', sin: 'sin', tan: 'tan', acos: 'acos', asin: 'asin',
  round: 'round', normalize: 'normalize', sign: 'sign', inversesqrt: 'inverseSqrt' };
const SPLAT = { min: 'min', max: 'max', clamp: 'clamp', mix: 'mix', step: 'step', pow: 'pow' };
const BITS = { floatBitsToUint: ['float', 'uint', 'u32'], floatBitsToInt: ['float', 'int', 'i32'],
  uintBitsToFloat: ['uint', 'float', 'f32'], intBitsToFloat: ['int', 'float', 'f32'] };

export class ExprEmitter {
  /** WGSL name of a GLSL identifier: reserved words get a `_` suffix; a clash of names throws. */
  nm(name, at) {
    if (name.startsWith('__') || name === '_') fail(at, `identifier '${name}' is not valid in WGSL`);
    if (!RESERVED.has(name)) return name;
    if (this.allIds && this.allIds.has(name + '_')) fail(at, `renaming '${name}' to '${name}_' clashes with an existing name`);
    this.renamed.add(name);
    return name + '_';
  }
  lookup(name, at) {
    for (let s = this.scopes.length - 1; s >= 0; --s) if (this.scopes[s].has(name)) return this.scopes[s].get(name);
    fail(at, `unknown identifier '${name}'`);
  }
  type(name, size, at) {
    const t = typeOf(name, size, this.structs, at);
    if (t.arr && t.size) {
      const s = this.ex(t.size);
      if (!isInt(s.t) || s.t.n !== 1) fail(at, 'array size is not an integer');
      t.sizeText = s.c;
    }
    return t;
  }
  /** r converted to scalar base b (GLSL's implicit int -> uint, int/uint -> float, or explicit). */
  toBase(r, b, at, explicit = false) {
    if (r.t.b === b) return r;
    if (!explicit && !(isNum(r.t) && RANK[b] > RANK[r.t.b])) fail(at, `no implicit conversion from ${glslName(r.t)} to ${b}`);
    const t = { b, n: r.t.n };
    if (r.abs && /^[0-9]/.test(r.c) && (b === 'float' || r.t.b === 'int')) return { ...r, t };
    return { ...r, c: `${wgslType(t)}(${r.c})`, t, abs: false, cls: null };
  }
  /** r as a value of type t (an initialiser, argument, return value or assigned value). */
  implicit(r, t, at) {
    if (same(r.t, t)) return r;
    if (r.t.b && t.b && r.t.n === t.n) return this.toBase(r, t.b, at);
    fail(at, `cannot convert ${glslName(r.t)} to ${glslName(t)}`);
  }
  concrete(r) {
    return r.abs ? { ...r, c: `${SCALAR[r.t.b]}(${r.c})`, abs: false, cls: null } : r;
  }

  ex(e) {
    switch (e.k) {
      case 'paren': return this.ex(e.a);
      case 'lit': return this.literal(e);
      case 'id': return this.ident(e);
      case 'mem': return this.member(e);
      case 'idx': {
        const a = this.ex(e.a), i = this.ex(e.i);
        if (!isInt(i.t) || i.t.n !== 1) fail(e.loc, 'index is not an integer');
        let t;
        if (a.t.arr) t = a.t.arr;
        else if (a.t.b && a.t.n > 1) t = { b: a.t.b, n: 1 };
        else if (a.t.mat) t = { b: 'float', n: 3 };
        else fail(e.loc, `cannot index ${glslName(a.t)}`);
        return { c: `${postfixable(a)}[${i.c}]`, t, pure: pure(a, i), root: a.root };
      }
      case 'call': return this.call(e);
      case 'length': {  // GLSL .length() is an int; a runtime-sized array's is arrayLength's u32
        const a = this.ex(e.a);
        if (!a.t.arr) fail(e.loc, `.length() of ${glslName(a.t)}`);
        if (a.t.sizeText !== undefined) return { c: `i32(${a.t.sizeText})`, t: INT, pure: true };
        if (!a.root || !['ro', 'storage-w'].includes(a.root.kind)) fail(e.loc, '.length() of a runtime array outside a buffer');
        return { c: `i32(arrayLength(&${a.c}))`, t: INT, pure: true };
      }
      case 'un': return this.unary(e);
      case 'bin': return this.binary(e);
      case 'cond': return this.cond(e);
      case 'assign': fail(e.loc, 'assignment inside an expression is not supported');
      // falls through (fail throws)
      case 'pre': case 'post': fail(e.loc, `'${e.op}' inside an expression is not supported (only as a statement)`);
      // falls through
      default: fail(e.loc, `unsupported expression ${e.k}`);
    }
  }
  literal(e) {
    const v = e.v;
    if (v === 'true' || v === 'false') return { c: v, t: BOOL, pure: true };
    if (/^0[xX]/.test(v)) {
      if (/[uU]$/.test(v)) return { c: v.slice(0, -1) + 'u', t: UINT, pure: true };
      if (parseInt(v, 16) > 0x7fffffff) fail(e.loc, `hex literal ${v} overflows int`);
      return { c: v, t: INT, abs: true, pure: true };
    }
    if (/[uU]$/.test(v)) return { c: v.slice(0, -1) + 'u', t: UINT, pure: true };
    if (/[.eE]/.test(v) || /[fF]$/.test(v)) {
      let c = v.replace(/[fF]$/, '');
      if (c.startsWith('.')) c = '0' + c;
      if (!/[.eE]/.test(c)) c += '.0';
      return { c, t: FLOAT, abs: true, pure: true };
    }
    return { c: v, t: INT, abs: true, pure: true };
  }
  ident(e) {
    const s = this.lookup(e.name, e.loc);
    if (s.kind === 'builtin' && !this.cur?.main) fail(e.loc, `${e.name} outside main`);
    return { c: s.kind === 'ptr' ? `(*${s.c})` : s.c, t: s.t, pure: true, root: s, abs: false };
  }
  member(e) {
    const a = this.ex(e.a);
    if (a.t.st) {
      const m = this.structs.get(a.t.st).find((x) => x.name === e.name);
      if (!m) fail(e.loc, `${a.t.st} has no member ${e.name}`);
      return { c: `${postfixable(a)}.${this.nm(e.name, e.loc)}`, t: m.t, pure: a.pure, root: a.root };
    }
    if (!a.t.b) fail(e.loc, `.${e.name} on ${glslName(a.t)}`);
    const sets = ['xyzw', 'rgba', 'stpq'];
    const set = sets.find((s) => [...e.name].every((ch) => s.slice(0, a.t.n).includes(ch)));
    if (!set || e.name.length > 4) fail(e.loc, `invalid swizzle .${e.name} of ${glslName(a.t)}`);
    const sw = [...e.name].map((ch) => 'xyzw'[set.indexOf(ch)]).join('');
    return { c: `${postfixable(a)}.${set === 'rgba' ? e.name : sw}`, t: { b: a.t.b, n: sw.length }, pure: a.pure,
      root: a.root, swizzle: sw.length, abs: false };
  }
  unary(e) {
    const a = this.ex(e.a);
    const inner = a.cls || /^-/.test(a.c) ? `(${a.c})` : a.c;
    if (e.op === '+') return a;
    if (e.op === '-') {
      if (!isNum(a.t) && !a.t.mat) fail(e.loc, `unary - on ${glslName(a.t)}`);
      if (a.t.b === 'uint') fail(e.loc, 'unary - on uint');
      return { c: `-${inner}`, t: a.t, abs: a.abs, pure: a.pure, cls: 'un' };
    }
    if (e.op === '!') {
      if (!same(a.t, BOOL)) fail(e.loc, `! on ${glslName(a.t)}`);
      return { c: `!${inner}`, t: BOOL, pure: a.pure, cls: 'un' };
    }
    if (!isInt(a.t)) fail(e.loc, `~ on ${glslName(a.t)}`);
    return { c: `~${inner}`, t: a.t, pure: a.pure, cls: 'un' };
  }
  binary(e) {
    const op = e.op;
    let a = this.ex(e.a), b = this.ex(e.b);
    const out = (t, x, y) => ({ c: `${operand(op, x, false)} ${op} ${operand(op, y, true)}`, t, pure: pure(x, y),
      cls: CLS[op], op });
    if (op === '&&' || op === '||') {
      if (!same(a.t, BOOL) || !same(b.t, BOOL)) fail(e.loc, `${op} needs bool operands`);
      return out(BOOL, a, b);
    }
    if (op === '<<' || op === '>>') {
      if (!isInt(a.t) || !isInt(b.t)) fail(e.loc, `${op} needs integer operands`);
      if (b.t.n !== 1 && b.t.n !== a.t.n) fail(e.loc, `${op} operand sizes differ`);
      if (b.abs && /^[0-9]/.test(b.c)) b = { ...b, c: `${b.c}u`, t: { b: 'uint', n: 1 }, abs: false };
      else if (b.t.b !== 'uint') b = this.toBase(b, 'uint', e.loc, true);
      if (a.t.n > 1 && b.t.n === 1) b = { ...b, c: `vec${a.t.n}<u32>(${b.c})`, cls: null };
      return out(a.t, this.concrete(a), b);
    }
    if (!a.t.b && !a.t.mat) fail(e.loc, `${op} on ${glslName(a.t)}`);
    if (!b.t.b && !b.t.mat) fail(e.loc, `${op} on ${glslName(b.t)}`);
    if (a.t.mat || b.t.mat) {
      if (op !== '*' || !a.t.mat || !(b.t.b === 'float' && b.t.n === 3)) fail(e.loc, `matrix ${op} is not supported`);
      return out({ b: 'float', n: 3 }, a, b);
    }
    if (a.t.b !== b.t.b) {
      if (a.t.b === 'bool' || b.t.b === 'bool') fail(e.loc, `${op} mixes bool and numbers`);
      if (RANK[a.t.b] < RANK[b.t.b]) a = this.toBase(a, b.t.b, e.loc); else b = this.toBase(b, a.t.b, e.loc);
    }
    if (a.abs && b.abs) a = this.concrete(a);  // GLSL evaluates in the type; WGSL would in abstract precision
    const n = Math.max(a.t.n, b.t.n);
    if (a.t.n !== b.t.n && a.t.n !== 1 && b.t.n !== 1) fail(e.loc, `${op} on vectors of different sizes`);
    if (CLS[op] === 'rel') {
      if (n > 1) fail(e.loc, `${op} on vectors (GLSL gives a bool, WGSL a bool vector)`);
      if (a.t.b === 'bool' && op !== '==' && op !== '!=') fail(e.loc, `${op} on bool`);
      return out(BOOL, a, b);
    }
    if (a.t.b === 'bool') fail(e.loc, `${op} on bool`);
    if ((CLS[op] === 'bit' || op === '%') && !isInt(a.t)) fail(e.loc, `${op} needs integer operands`);
    if (CLS[op] === 'bit' && a.t.n !== b.t.n) fail(e.loc, `${op} of a vector and a scalar`);
    return out({ b: a.t.b, n }, a, b);
  }
  /** c ? a : b as select(b, a, c): both arms are evaluated, so both must be free of side effects. */
  cond(e) {
    const c = this.ex(e.c);
    let a = this.ex(e.a), b = this.ex(e.b);
    if (!same(c.t, BOOL)) fail(e.loc, '?: condition is not a bool');
    if (!a.t.b || !b.t.b) fail(e.loc, `?: on ${glslName(a.t)} (select takes scalars and vectors)`);
    if (!pure(a, b)) fail(e.loc, '?: with a side effect in an arm (select evaluates both arms)');
    if (a.t.b !== b.t.b) {
      if (RANK[a.t.b] < RANK[b.t.b]) a = this.toBase(a, b.t.b, e.loc); else b = this.toBase(b, a.t.b, e.loc);
    }
    if (a.t.n !== b.t.n) fail(e.loc, '?: arms of different sizes');
    return { c: `select(${b.c}, ${a.c}, ${c.c})`, t: a.t, abs: a.abs && b.abs, pure: pure(a, b, c) };
  }

  call(e) {
    if (e.arr !== undefined) {
      const t = this.type(e.name, e.arr, e.loc);
      const args = e.args.map((x) => this.implicit(this.ex(x), t.arr, x.loc));
      if (String(args.length) !== t.sizeText) fail(e.loc, `array constructor with ${args.length} elements`);
      return { c: `${wgslType(t)}(${args.map((r) => r.c).join(', ')})`, t, pure: pure(...args) };
    }
    if (this.structs.has(e.name)) {
      const ms = this.structs.get(e.name);
      if (ms.length !== e.args.length) fail(e.loc, `${e.name} constructor takes ${ms.length} arguments`);
      const args = e.args.map((x, i) => this.implicit(this.ex(x), ms[i].t, x.loc));
      return { c: `${e.name}(${args.map((r) => r.c).join(', ')})`, t: { st: e.name }, pure: pure(...args) };
    }
    if (SCALAR[e.name] || /^[iub]?vec[234]$/.test(e.name) || e.name === 'mat3') return this.construct(e);
    if (this.fns.has(e.name)) return this.userCall(e);
    return this.builtin(e);
  }
  construct(e) {
    const t = typeOf(e.name, undefined, this.structs, e.loc);
    const args = e.args.map((x) => this.ex(x));
    const list = (rs) => rs.map((r) => r.c).join(', ');
    if (t.mat) {
      if (args.length !== 3 || !args.every((r) => r.t.b === 'float' && r.t.n === 3)) fail(e.loc, 'mat3 takes three vec3 columns here');
      return { c: `mat3x3<f32>(${list(args)})`, t, pure: pure(...args) };
    }
    if (args.some((r) => !r.t.b)) fail(e.loc, `${e.name} of a non-numeric argument`);
    if (args.length === 1) {
      let a = args[0];
      if (a.t.n > t.n) fail(e.loc, `${e.name} of a larger ${glslName(a.t)} (take a swizzle)`);
      if (a.t.n > 1 && a.t.n !== t.n) fail(e.loc, `${e.name} of ${glslName(a.t)}`);
      if (t.n > 1 && a.t.n === 1 && a.t.b !== t.b) a = this.toBase(a, t.b, e.loc, true);
      return { c: `${wgslType(t)}(${a.c})`, t, pure: a.pure };
    }
    if (t.n === 1) fail(e.loc, `${e.name} with ${args.length} arguments`);
    const conv = args.map((r) => (r.t.b === t.b ? r : r.t.n === 1 ? this.toBase(r, t.b, e.loc, true)
      : { ...r, c: `${wgslType({ b: t.b, n: r.t.n })}(${r.c})` }));
    if (conv.reduce((s, r) => s + r.t.n, 0) !== t.n) fail(e.loc, `${e.name} with the wrong number of components`);
    return { c: `${wgslType(t)}(${list(conv)})`, t, pure: pure(...args) };
  }
  /** A call of a function of the source: out and inout arguments become pointers to local variables. */
  userCall(e) {
    const f = this.fns.get(e.name);
    if (f.params.length !== e.args.length) fail(e.loc, `${e.name} takes ${f.params.length} arguments`);
    const outs = new Set();
    const args = e.args.map((x, i) => {
      const p = f.params[i];
      if (p.dir === 'in') return this.implicit(this.ex(x), p.t, x.loc).c;
      return this.outArg(x, p.t, outs);
    });
    this.cur.calls.add(e.name);
    if (!f.pureFn) this.cur.pureFn = false;
    const isPure = f.pureFn && f.params.every((p) => p.dir === 'in');
    return { c: `${this.nm(e.name, e.loc)}(${args.join(', ')})`, t: f.ret, pure: isPure, call: true };
  }
  /** An out/inout argument: a local variable (`&x`) or the caller's own pointer parameter. */
  outArg(x, t, outs) {
    if (x.k !== 'id') fail(x.loc, 'an out argument must be a local variable (not a member, element or expression)');
    const s = this.lookup(x.name, x.loc);
    if (s.kind !== 'var' && s.kind !== 'ptr') fail(x.loc, `out argument ${x.name} is not a local variable`);
    if (!same(s.t, t)) fail(x.loc, `out argument ${x.name} is ${glslName(s.t)}, the parameter ${glslName(t)}`);
    if (outs.has(x.name)) fail(x.loc, `${x.name} passed to two out parameters`);
    outs.add(x.name);
    return s.kind === 'ptr' ? s.c : `&${s.c}`;
  }

  builtin(e) {
    const name = e.name, at = e.loc;
    const args = e.args.map((x) => this.ex(x));
    const n = args.length;
    const res = (c, t, extra = {}) => ({ c, t, pure: pure(...args), ...extra });
    const float = (r) => (r.t.b === 'float' ? r : this.toBase(r, 'float', at));
    const argc = (k) => { if (n !== k) fail(at, `${name} with ${n} arguments`); };
    if (SAME[name]) {
      argc(1);
      const a = name === 'abs' || name === 'sign' ? args[0] : float(args[0]);
      if (!isNum(a.t)) fail(at, `${name} of ${glslName(a.t)}`);
      return res(`${SAME[name]}(${a.c})`, a.t);
    }
    if (name === 'fma') {  // scalar only; WGSL's fma may be unfused (see the header)
      argc(3);
      const fs = args.map((r) => this.concrete(float(r)));
      if (fs.some((r) => r.t.n !== 1)) fail(at, 'fma of vectors is not translated');
      return res(`fma(${fs.map((r) => r.c).join(', ')})`, FLOAT);
    }
    if (SPLAT[name]) return this.splatCall(name, args, at);
    if (name === 'dot' || name === 'length') {
      argc(name === 'dot' ? 2 : 1);
      const fs = args.map(float);
      if (name === 'dot' && !same(fs[0].t, fs[1].t)) fail(at, 'dot of different types');
      return res(`${name}(${fs.map((r) => r.c).join(', ')})`, FLOAT);
    }
    if (name === 'atan') {
      const fs = args.map(float);
      if (n === 1) return res(`atan(${fs[0].c})`, fs[0].t);
      argc(2);
      if (!same(fs[0].t, fs[1].t)) fail(at, 'atan of different types');
      return res(`atan2(${fs[0].c}, ${fs[1].c})`, fs[0].t);
    }
    if (name === 'isnan' || name === 'isinf') {
      argc(1);
      if (!same(args[0].t, FLOAT)) fail(at, `${name} of ${glslName(args[0].t)} (only float is translated)`);
      this.helpers.add(name);
      return res(`glsl_${name}(${this.concrete(args[0]).c})`, BOOL);
    }
    if (BITS[name]) {
      argc(1);
      const [from, to, w] = BITS[name];
      const a = args[0];
      if (a.t.b !== from) fail(at, `${name} of ${glslName(a.t)}`);
      const t = { b: to, n: a.t.n };
      if (a.abs || /^[0-9]/.test(a.c)) {  // a constant
        if (name !== 'uintBitsToFloat' || a.t.n !== 1) fail(at, `${name} of a constant`);
        this.helpers.add('uintBitsToFloat');
        return res(`glsl_uintBitsToFloat(${a.c})`, t);
      }
      return res(`bitcast<${a.t.n === 1 ? w : `vec${a.t.n}<${w}>`}>(${a.c})`, t);
    }
    if (name === 'umulExtended') {
      argc(4);
      const [a, b] = args.slice(0, 2).map((r) => this.implicit(r, UINT, at));
      const outs = new Set();
      const hi = this.outArg(e.args[2], UINT, outs), lo = this.outArg(e.args[3], UINT, outs);
      this.helpers.add('umulExtended');
      return { c: `glsl_umulExtended(${a.c}, ${b.c}, ${hi}, ${lo})`, t: { void: true }, pure: false, call: true };
    }
    if (name === 'texelFetch') return this.texelFetch(e, args);
    if (name === 'textureSize') {  // an array texture's layer count is textureNumLayers
      argc(2);
      const tex = args[0].t.tex;
      if (!tex || e.args[0].k !== 'id') fail(at, 'textureSize of a non-sampler');
      const lod = this.implicit(args[1], INT, at);
      if (!TEXTURES[tex][2]) return res(`vec3<i32>(textureDimensions(${args[0].c}, ${lod.c}))`, { b: 'int', n: 3 });
      return res(`vec3<i32>(vec3<u32>(textureDimensions(${args[0].c}, ${lod.c}), textureNumLayers(${args[0].c})))`, { b: 'int', n: 3 });
    }
    if (name === 'mod') fail(at, 'GLSL mod (x - y floor(x / y)) differs from WGSL % for floats and is not translated');
    fail(at, `builtin ${name} is not translated`);
  }
  /** min, max, clamp, mix, step, pow: one base type, scalars splatted to the vector arguments' size. */
  splatCall(name, args, at) {
    const n = Math.max(...args.map((r) => r.t.n));
    if (args.some((r) => !isNum(r.t))) fail(at, `${name} of a non-numeric argument`);
    const floatOnly = ['mix', 'step', 'pow'].includes(name);
    const b = floatOnly ? 'float' : args.reduce((m, r) => (RANK[r.t.b] > RANK[m] ? r.t.b : m), 'int');
    const want = { mix: 3, step: 2, pow: 2, clamp: 3, min: 2, max: 2 }[name];
    if (args.length !== want) fail(at, `${name} with ${args.length} arguments`);
    if (name === 'mix' && args[2].t.b === 'bool') fail(at, 'mix with a bool selector');
    const conv = args.map((r) => {
      let x = r.t.b === b ? r : this.toBase(r, b, at);
      if (x.t.n === 1 && n > 1) x = { ...x, c: `${wgslType({ b, n })}(${x.c})`, t: { b, n }, abs: false };
      if (x.t.n !== n) fail(at, `${name} of vectors of different sizes`);
      return x;
    });
    const allAbs = conv.every((r) => r.abs);
    return { c: `${name}(${conv.map((r) => r.c).join(', ')})`, t: { b, n }, abs: allAbs, pure: pure(...args) };
  }
  texelFetch(e, args) {
    if (args.length !== 3 || e.args[0].k !== 'id') fail(e.loc, 'texelFetch(sampler, coordinate, lod) expected');
    const tex = args[0].t.tex;
    if (!tex) fail(e.loc, 'texelFetch of a non-sampler');
    const [, b, layered] = TEXTURES[tex];
    const c = args[1], lod = this.implicit(args[2], INT, e.loc);
    if (c.t.b !== 'int' || c.t.n !== 3) fail(e.loc, `texelFetch coordinate ${glslName(c.t)} (ivec3 expected)`);
    const t = { b, n: 4 };
    if (!layered) return { c: `textureLoad(${args[0].c}, ${c.c}, ${lod.c})`, t, pure: true };
    this.helpers.add(`texelFetch_${tex}`);
    return { c: `glsl_texelFetch_${tex}(${args[0].c}, ${c.c}, ${lod.c})`, t, pure: pure(c, lod) };
  }
}
