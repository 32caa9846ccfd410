// scene_description.js - a reader of scene descriptions (spec/scene.md), written from the spec: the
// JSON text rules of section 1, the uri rules of section 3 and the rules of section 5, checked in
// the order of its table (normative for the first error), with the same IDs as libvff.
//
//   import { readSceneDescription, resolveSceneUri } from './src/scene_description.js';
//   const scene = readSceneDescription(bytes, 'courtyard.vffscene.json');  // throws SceneError
//   for (const f of scene.fields) fetch(resolveSceneUri('courtyard.vffscene.json', f.uri));
//
// JSON.parse cannot be used: it keeps the last of two repeated names, has no depth limit, turns
// 1e400 into Infinity without a word and cannot say where a problem is. The parser below works on
// the bytes, so that columns count bytes as the spec says.

/** The rule names of spec/scene.md section 5. */
export const SCENE_CODE_NAMES = Object.freeze({
  11001: 'scene-json', 11002: 'scene-version', 11003: 'scene-value', 11004: 'scene-uri', 11005: 'scene-field-index',
});

/** How deep objects and arrays may nest (spec/scene.md section 1, rule 3). */
export const MAX_JSON_DEPTH = 64;

// The range of an integer (spec/scene.md section 1): readers hold integers in 64 bits.
const INT64_MIN = -(2n ** 63n);
const UINT64_MAX = 2n ** 64n - 1n;

/** A scene description that breaks a rule: `id` is the rule's ID, `codeName` its name. */
export class SceneError extends Error {
  constructor(id, message) {
    super(`${SCENE_CODE_NAMES[id]} (${id}): ${message}`);
    this.id = id;
    this.codeName = SCENE_CODE_NAMES[id];
    this.detail = message;
  }
}

// ---- The JSON text (section 1) ----------------------------------------------------------------------

class JsonProblem extends Error {
  constructor(at, path, what) {
    super(what);
    this.at = at;
    this.path = path;
  }
}

const isPlainKey = (k) => /^[A-Za-z_][A-Za-z0-9_]*$/.test(k);
const keySegment = (k) => (isPlainKey(k) ? `.${k}` : `[${JSON.stringify(k)}]`);
const joinPath = (segments) => segments.join('').replace(/^\./, '');

/** A JSON value with the kind of number it was written as kept: numbers become {num: value}, and
 * integers {num: value, int: exact value as a BigInt}. */
class Parser {
  constructor(bytes) {
    this.b = bytes;
    this.i = 0;
    this.path = [];
  }

  fail(what, at = this.i) { throw new JsonProblem(at, joinPath(this.path), what); }

  ws() {
    const b = this.b;
    while (this.i < b.length && (b[this.i] === 0x20 || b[this.i] === 0x09 || b[this.i] === 0x0a || b[this.i] === 0x0d)) this.i++;
  }

  document() {
    if (this.b[0] === 0xef && this.b[1] === 0xbb && this.b[2] === 0xbf) this.i = 3;
    this.ws();
    const v = this.value(1);
    this.ws();
    if (this.i < this.b.length) {
      this.fail(this.b[this.i] === 0 ? 'a NUL byte after the JSON value (only whitespace may follow it)'
        : 'a byte after the JSON value (only whitespace may follow it)');
    }
    return v;
  }

  value(depth) {
    const c = this.b[this.i];
    if (c === undefined) this.fail('the text ends where a value should begin');
    if (c === 0x7b || c === 0x5b) {
      if (depth > MAX_JSON_DEPTH) this.fail(`objects and arrays nest deeper than ${MAX_JSON_DEPTH} (a reader limit)`);
      return c === 0x7b ? this.object(depth) : this.array(depth);
    }
    if (c === 0x22) return this.string();
    if (c === 0x2d || (c >= 0x30 && c <= 0x39)) return this.number();
    for (const [word, v] of [['true', true], ['false', false], ['null', null]]) {
      if (this.b.subarray(this.i, this.i + word.length).every((x, k) => x === word.charCodeAt(k))
          && this.i + word.length <= this.b.length) {
        this.i += word.length;
        return v;
      }
    }
    return this.fail(c === 0 ? 'a NUL byte' : 'not the start of a JSON value');
  }

  object(depth) {
    const out = new Map();
    this.i++;
    this.ws();
    if (this.b[this.i] === 0x7d) { this.i++; return out; }
    this.path.push('');
    for (;;) {
      this.ws();
      if (this.b[this.i] !== 0x22) this.fail('a member name (a string) is expected');
      const at = this.i;
      const key = this.string();
      this.path[this.path.length - 1] = keySegment(key);
      if (out.has(key)) this.fail(`the member name ${JSON.stringify(key)} is repeated in one object`, at);
      this.ws();
      if (this.b[this.i] !== 0x3a) this.fail("':' is expected");
      this.i++;
      this.ws();
      out.set(key, this.value(depth + 1));
      this.ws();
      if (this.b[this.i] === 0x2c) { this.i++; continue; }
      if (this.b[this.i] === 0x7d) { this.i++; break; }
      this.fail("',' or '}' is expected");
    }
    this.path.pop();
    return out;
  }

  array(depth) {
    const out = [];
    this.i++;
    this.ws();
    if (this.b[this.i] === 0x5d) { this.i++; return out; }
    this.path.push('');
    for (;;) {
      this.path[this.path.length - 1] = `[${out.length}]`;
      this.ws();
      out.push(this.value(depth + 1));
      this.ws();
      if (this.b[this.i] === 0x2c) { this.i++; continue; }
      if (this.b[this.i] === 0x5d) { this.i++; break; }
      this.fail("',' or ']' is expected");
    }
    this.path.pop();
    return out;
  }

  number() {
    const start = this.i;
    const rest = new TextDecoder('latin1').decode(this.b.subarray(start, Math.min(this.b.length, start + 1100)));
    const m = /^-?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?/.exec(rest);
    if (!m) this.fail('not a JSON number');
    this.i += m[0].length;
    const num = Number(m[0]);
    if (!Number.isFinite(num)) this.fail(`the number ${m[0]} is not representable as a finite binary64`, start);
    // An integer is written without a fraction or an exponent and held in 64 bits (spec/scene.md
    // section 1); `int` keeps its exact value, since a binary64 cannot (2^64 - 1 rounds to 2^64).
    if (m[2] === undefined && m[3] === undefined) {
      const int = BigInt(m[0]);
      if (int >= INT64_MIN && int <= UINT64_MAX) return { num: num + 0, int };  // + 0: -0 is the integer 0
    }
    return { num };
  }

  hex4() {
    const s = new TextDecoder('latin1').decode(this.b.subarray(this.i, this.i + 4));
    if (!/^[0-9A-Fa-f]{4}$/.test(s)) this.fail('a \\u escape needs four hex digits');
    this.i += 4;
    return parseInt(s, 16);
  }

  string() {
    const b = this.b;
    let out = '';
    this.i++;
    for (;;) {
      const c = b[this.i];
      if (c === undefined) this.fail('the text ends inside a string');
      if (c === 0x22) { this.i++; return out; }
      if (c < 0x20) this.fail('a control character in a string (escape it)');
      if (c === 0x5c) {
        const e = b[this.i + 1];
        this.i += 2;
        const simple = { 0x22: '"', 0x5c: '\\', 0x2f: '/', 0x62: '\b', 0x66: '\f', 0x6e: '\n', 0x72: '\r', 0x74: '\t' }[e];
        if (simple !== undefined) { out += simple; continue; }
        if (e !== 0x75) this.fail('an invalid escape', this.i - 1);
        const u = this.hex4();
        if (u >= 0xdc00 && u <= 0xdfff) this.fail('a low surrogate escape without a high one before it');
        if (u >= 0xd800 && u <= 0xdbff) {
          if (b[this.i] !== 0x5c || b[this.i + 1] !== 0x75) this.fail('a high surrogate escape without a low one after it');
          this.i += 2;
          const lo = this.hex4();
          if (lo < 0xdc00 || lo > 0xdfff) this.fail('a high surrogate escape without a low one after it');
          out += String.fromCharCode(u, lo);
        } else {
          out += String.fromCharCode(u);
        }
        continue;
      }
      const n = c < 0x80 ? 0 : (c >> 5) === 6 ? 1 : (c >> 4) === 14 ? 2 : (c >> 3) === 30 ? 3 : -1;
      if (n < 0) this.fail('ill-formed UTF-8');
      let cp = n === 0 ? c : c & (0x3f >> n);
      for (let k = 1; k <= n; k++) {
        const d = b[this.i + k];
        if (d === undefined || (d & 0xc0) !== 0x80) this.fail('ill-formed UTF-8');
        cp = (cp << 6) | (d & 0x3f);
      }
      if (cp < [0, 0x80, 0x800, 0x10000][n] || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) this.fail('ill-formed UTF-8');
      out += String.fromCodePoint(cp);
      this.i += n + 1;
    }
  }
}

function place(bytes, at) {
  let line = 1, column = 1;
  for (let k = 0; k < at && k < bytes.length; k++) {
    if (bytes[k] === 0x0a) { line++; column = 1; } else column++;
  }
  return { line, column };
}

/**
 * Checks and parses one JSON text by the rules of spec/scene.md section 1. Objects become Maps,
 * numbers {num} (integers {num, int}). Throws {line, column, path, message} (a plain object) on the first problem.
 */
export function parseStrictJson(bytes) {
  const p = new Parser(bytes);
  try {
    return p.document();
  } catch (e) {
    if (!(e instanceof JsonProblem)) throw e;
    const { line, column } = place(bytes, e.at);
    throw { byte: e.at, line, column, path: e.path, message: e.message };
  }
}

// ---- The values (sections 2 to 5) ---------------------------------------------------------------

const isNumber = (v) => v !== null && typeof v === 'object' && 'num' in v;
const isObject = (v) => v instanceof Map;
const isInteger = (v) => isNumber(v) && 'int' in v;

/** A value as messages quote it, cut short. */
function shown(v) {
  if (isInteger(v)) return String(v.int);  // exactly as written, as libvff quotes it
  // A number written with a fraction or an exponent but integral in value: "1.0", as libvff quotes
  // it, so that "is 1.0; this reader implements version 1" does not read as a contradiction.
  if (isNumber(v) && Number.isInteger(v.num) && Math.abs(v.num) < 1e15) return `${v.num + 0}.0`;
  const plain = (x) => (x instanceof Map ? Object.fromEntries([...x].map(([k, y]) => [k, plain(y)]))
    : Array.isArray(x) ? x.map(plain) : isNumber(x) ? x.num : x);
  const s = JSON.stringify(plain(v));
  return s.length > 40 ? `${s.slice(0, 37)}...` : s;
}

function checkUri(uri, bad) {
  if (uri === '') bad('is empty');
  const scheme = /^[A-Za-z][A-Za-z0-9+.-]*:/.exec(uri);
  if (scheme) {
    bad(scheme[0].length === 2 ? `'${uri}' starts with a Windows drive letter, which URI syntax reads as a scheme`
      : `'${uri}' has a URI scheme (${scheme[0]}); a file reference is required`);
  }
  if (uri.includes('\\')) bad(`'${uri}' has a backslash; the separator is '/'`);
  if (uri.startsWith('//')) bad(`'${uri}' starts with '//', a network-path reference`);
  if (/[?#]/.test(uri)) bad(`'${uri}' has a query or fragment ('?' or '#')`);
  const pct = /%(?![0-9A-Fa-f]{2})/.exec(uri);
  if (pct) bad(`'${uri}' has a '%' without two hex digits after it`);
  const bytes = percentDecodedBytes(uri);
  if (bytes.includes(0)) bad(`'${uri}' decodes to a NUL byte`);
  try {
    new TextDecoder('utf-8', { fatal: true }).decode(bytes);
  } catch {
    bad(`'${uri}' decodes to bytes that are not UTF-8`);
  }
}

function percentDecodedBytes(uri) {
  const src = new TextEncoder().encode(uri);
  const out = [];
  for (let k = 0; k < src.length; k++) {
    const hex = String.fromCharCode(src[k + 1] ?? 0, src[k + 2] ?? 0);
    if (src[k] === 0x25 && /^[0-9A-Fa-f]{2}$/.test(hex)) {
      out.push(parseInt(hex, 16));
      k += 2;
    } else {
      out.push(src[k]);
    }
  }
  return Uint8Array.from(out);
}

/** The file a field's `uri` names: decoded, then joined to the description's folder unless absolute. */
export function resolveSceneUri(descriptionPath, uri) {
  const path = new TextDecoder().decode(percentDecodedBytes(uri));
  if (path.startsWith('/')) return path;
  const slash = descriptionPath.lastIndexOf('/');
  return slash < 0 ? path : descriptionPath.slice(0, slash + 1) + path;
}

/**
 * Reads a scene description from its bytes; `name` names it in messages. Returns
 * {generator, fields: [{uri, name, source}], instances: [{field, name, translation, rotation, scale}]}
 * with the binary32 values as numbers (rotation normalised); throws SceneError.
 */
export function readSceneDescription(bytes, name) {
  let doc;
  try {
    doc = parseStrictJson(bytes);
  } catch (p) {
    if (!('line' in p)) throw p;
    throw new SceneError(11001, `${name}:${p.line}:${p.column}: ${p.path ? `${p.path}: ` : ''}${p.message}`);
  }
  const fail = (id, where, what) => { throw new SceneError(id, `${name}: ${where}: ${what}`); };
  const value = (where, what) => fail(11003, where, what);
  const missing = (where) => value(where, 'a required member is missing');
  const optionalString = (obj, key, where) => {
    if (!obj.has(key)) return '';
    const v = obj.get(key);
    if (typeof v !== 'string') value(`${where}.${key}`, `expected a string, got ${shown(v)}`);
    return v;
  };
  if (!isObject(doc)) throw new SceneError(11001, `${name}: the JSON value is not an object`);

  if (!doc.has('asset')) missing('asset');
  const asset = doc.get('asset');
  if (!isObject(asset)) value('asset', `expected an object, got ${shown(asset)}`);
  if (!asset.has('format')) missing('asset.format');
  if (asset.get('format') !== 'vff-scene') fail(11002, 'asset.format', `is ${shown(asset.get('format'))}, not "vff-scene"`);
  if (!asset.has('version')) missing('asset.version');
  const version = asset.get('version');
  if (!isInteger(version) || version.int !== 1n) fail(11002, 'asset.version', `is ${shown(version)}; this reader implements version 1`);
  if (asset.has('minorVersion')) {
    const m = asset.get('minorVersion');
    if (!isInteger(m) || m.int < 0n) value('asset.minorVersion', `expected a non-negative integer, got ${shown(m)}`);
  }
  const generator = optionalString(asset, 'generator', 'asset');
  for (const key of ['fields', 'instances']) {
    if (!doc.has(key)) missing(key);
    if (!Array.isArray(doc.get(key))) value(key, `expected an array, got ${shown(doc.get(key))}`);
  }

  const fields = doc.get('fields').map((f, i) => {
    const where = `fields[${i}]`;
    if (!isObject(f)) value(where, `expected an object, got ${shown(f)}`);
    if (!f.has('uri')) missing(`${where}.uri`);
    const uri = f.get('uri');
    if (typeof uri !== 'string') value(`${where}.uri`, `expected a string, got ${shown(uri)}`);
    checkUri(uri, (what) => fail(11004, `${where}.uri`, what));
    const fieldName = optionalString(f, 'name', where);
    if (f.has('source') && !isObject(f.get('source'))) value(`${where}.source`, `expected an object, got ${shown(f.get('source'))}`);
    return { uri, name: fieldName, source: f.get('source') ?? null };
  });

  const binary32 = (v, where) => {
    if (!isNumber(v)) value(where, `expected a number, got ${shown(v)}`);
    const f = Math.fround(v.num);
    if (!Number.isFinite(f)) value(where, `the number ${shown(v)} is not finite in binary32`);
    return f;
  };
  const numbers = (obj, key, n, where, fallback) => {
    if (!obj.has(key)) return fallback;
    const a = obj.get(key);
    if (!Array.isArray(a) || a.length !== n) value(`${where}.${key}`, `expected an array of ${n} numbers, got ${shown(a)}`);
    return a.map((v, k) => binary32(v, `${where}.${key}[${k}]`));
  };
  const instances = doc.get('instances').map((inst, i) => {
    const where = `instances[${i}]`;
    if (!isObject(inst)) value(where, `expected an object, got ${shown(inst)}`);
    if (!inst.has('field')) missing(`${where}.field`);
    const field = inst.get('field');
    if (!isInteger(field)) value(`${where}.field`, `expected an integer, got ${shown(field)}`);
    if (field.int < 0n || field.int >= BigInt(fields.length)) {
      fail(11005, `${where}.field`, `index ${shown(field)} is not one of the ${fields.length} fields`);
    }
    const instName = optionalString(inst, 'name', where);
    const translation = numbers(inst, 'translation', 3, where, [0, 0, 0]);
    const q = numbers(inst, 'rotation', 4, where, [0, 0, 0, 1]);
    const norm = Math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(Math.abs(norm - 1) <= 1e-3)) value(`${where}.rotation`, `the quaternion's norm is ${norm}, not within 1e-3 of 1`);
    const rotation = q.map((c) => Math.fround(c / norm));
    let scale = 1;
    if (inst.has('scale')) {
      scale = binary32(inst.get('scale'), `${where}.scale`);
      if (!(scale > 0)) value(`${where}.scale`, `must be positive in binary32, got ${shown(inst.get('scale'))}`);
    }
    return { field: field.num, name: instName, translation, rotation, scale };
  });
  return { generator, fields, instances };
}
