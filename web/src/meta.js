// meta.js - the META rule 8001 checker: exactly one RFC 8259 JSON text in strict UTF-8, surrogate
// escapes in pairs, at most 64 levels deep, numbers checked as text (spec/format.md section 9).

/** Returns null when the bytes are one JSON text, else {offset, message} of the first problem. */
export function checkJsonText(b) {
  let p = 0, depth = 0;
  const n = b.length;
  const fail = (m) => { throw { offset: p, message: m }; };
  const ws = () => { while (p < n && (b[p] === 0x20 || b[p] === 0x09 || b[p] === 0x0a || b[p] === 0x0d)) ++p; };
  const lit = (s) => {
    for (let i = 0; i < s.length; ++i) if (b[p + i] !== s.charCodeAt(i)) fail(`expected ${s}`);
    p += s.length;
  };
  const hex4 = () => {
    let v = 0;
    for (let i = 0; i < 4; ++i) {
      const c = b[p++];
      const d = c >= 0x30 && c <= 0x39 ? c - 0x30 : c >= 0x41 && c <= 0x46 ? c - 55 : c >= 0x61 && c <= 0x66 ? c - 87 : -1;
      if (d < 0) fail('bad \\u escape');
      v = v * 16 + d;
    }
    return v;
  };
  const string = () => {
    ++p;
    for (;;) {
      if (p >= n) fail('unterminated string');
      const c = b[p];
      if (c === 0x22) { ++p; return; }
      if (c < 0x20) fail('unescaped control character');
      if (c === 0x5c) {
        const e = b[p + 1];
        p += 2;
        if (e === 0x75) {
          const u = hex4();
          if (u >= 0xdc00 && u <= 0xdfff) fail('lone low surrogate escape');
          if (u >= 0xd800 && u <= 0xdbff) {
            if (b[p] !== 0x5c || b[p + 1] !== 0x75) fail('lone high surrogate escape');
            p += 2;
            const l = hex4();
            if (l < 0xdc00 || l > 0xdfff) fail('high surrogate escape without a low one');
          }
        } else if (![0x22, 0x5c, 0x2f, 0x62, 0x66, 0x6e, 0x72, 0x74].includes(e)) fail('bad escape');
        continue;
      }
      if (c < 0x80) { ++p; continue; }
      // UTF-8, RFC 3629: shortest form, no surrogates, nothing above U+10FFFF.
      let len, lo = 0x80, hi = 0xbf;
      if (c >= 0xc2 && c <= 0xdf) len = 2;
      else if (c >= 0xe0 && c <= 0xef) { len = 3; if (c === 0xe0) lo = 0xa0; if (c === 0xed) hi = 0x9f; }
      else if (c >= 0xf0 && c <= 0xf4) { len = 4; if (c === 0xf0) lo = 0x90; if (c === 0xf4) hi = 0x8f; }
      else fail('invalid UTF-8');
      for (let i = 1; i < len; ++i) {
        const t = b[p + i];
        if (t === undefined || t < (i === 1 ? lo : 0x80) || t > (i === 1 ? hi : 0xbf)) fail('invalid UTF-8');
      }
      p += len;
    }
  };
  const digits = () => { const s = p; while (p < n && b[p] >= 0x30 && b[p] <= 0x39) ++p; if (p === s) fail('digit expected'); };
  const number = () => {
    if (b[p] === 0x2d) ++p;
    if (b[p] === 0x30) ++p; else digits();
    if (b[p] === 0x2e) { ++p; digits(); }
    if (b[p] === 0x65 || b[p] === 0x45) { ++p; if (b[p] === 0x2b || b[p] === 0x2d) ++p; digits(); }
  };
  const value = () => {
    ws();
    const c = b[p];
    if (c === 0x7b || c === 0x5b) {
      if (++depth > 64) fail('nested deeper than 64 levels');
      const close = c === 0x7b ? 0x7d : 0x5d;
      ++p; ws();
      if (b[p] === close) { ++p; --depth; return; }
      for (;;) {
        if (close === 0x7d) { ws(); if (b[p] !== 0x22) fail('key expected'); string(); ws(); if (b[p] !== 0x3a) fail(': expected'); ++p; }
        value(); ws();
        if (b[p] === 0x2c) { ++p; continue; }
        if (b[p] === close) { ++p; --depth; return; }
        fail(', or closing bracket expected');
      }
    }
    if (c === 0x22) return string();
    if (c === 0x74) return lit('true');
    if (c === 0x66) return lit('false');
    if (c === 0x6e) return lit('null');
    if (c === 0x2d || (c >= 0x30 && c <= 0x39)) return number();
    fail(p >= n ? 'value expected' : 'unexpected byte');
  };
  try {
    value();
    ws();
    if (p !== n) fail('bytes after the JSON value');
  } catch (e) {
    if (e instanceof Error) throw e;
    return e;
  }
  return null;
}

// The raw texts of the numbers that are members of the top-level "vff.partial" object (the last
// such member wins, as in JSON.parse), and whether any number of the text lies beyond binary64. The
// text is one valid JSON text (rule 8001 passed). JSON.parse keeps neither `3` apart from `3.0` nor
// fails on `1e400`, where vff-inspect's parser (nlohmann-json) does both.
function partialNumberTexts(text) {
  let raw = {}, overflow = false, expectKey = false;
  const stack = [], keyAt = [];
  for (let i = 0; i < text.length;) {
    const c = text[i];
    if (c === '"') {
      let j = i + 1;
      while (text[j] !== '"') j += text[j] === '\\' ? 2 : 1;
      if (expectKey) {
        keyAt[stack.length - 1] = JSON.parse(text.slice(i, j + 1));
        if (stack.length === 1 && keyAt[0] === 'vff.partial') raw = {};
        expectKey = false;
      }
      i = j + 1;
    } else if (c === '{' || c === '[') {
      stack.push(c);
      expectKey = c === '{';
      ++i;
    } else if (c === '}' || c === ']') {
      stack.pop();
      ++i;
    } else if (c === ',') {
      expectKey = stack[stack.length - 1] === '{';
      ++i;
    } else if (c === '-' || (c >= '0' && c <= '9')) {
      let j = i + 1;
      while (j < text.length && '0123456789eE+-.'.includes(text[j])) ++j;
      const t = text.slice(i, j);
      if (!Number.isFinite(Number(t))) overflow = true;
      if (stack.length === 2 && stack[0] === '{' && stack[1] === '{' && keyAt[0] === 'vff.partial') raw[keyAt[1]] = t;
      i = j;
    } else {
      ++i;
    }
  }
  return { raw, overflow };
}

/**
 * A partial result (spec/partial.md: META has "vff.partial"): null for a whole field, else
 * {mapBegin, mapEnd, mapCount, maps} as vff-inspect --format json reports it ("partial"), with
 * mapBegin, mapEnd and maps null when "vff.partial" gives no range mapBegin < mapEnd <= mapCount =
 * the field's mapCount. `meta` is the parsed META object (or null), `fieldMapCount` FDSC mapCount,
 * `text` META's text: given, the bounds count only when written as integers (`3`, not `3.0`, `3e0`
 * or `-0`), and a META with a number beyond binary64 is no partial result, as vff-inspect reads it.
 */
export function partialRange(meta, fieldMapCount, text = undefined) {
  if (!meta || typeof meta !== 'object' || !Object.hasOwn(meta, 'vff.partial')) return null;
  const numbers = text === undefined ? null : partialNumberTexts(text);
  if (numbers?.overflow) return null;
  const p = meta['vff.partial'];
  const written = (k) => numbers === null || /^(0|[1-9][0-9]*)$/.test(numbers.raw[k] ?? '');
  const u32 = (k) => p && typeof p === 'object' && !Array.isArray(p) && Number.isInteger(p[k]) && p[k] >= 0 &&
    p[k] <= 0xffffffff && written(k);
  if (u32('mapBegin') && u32('mapEnd') && u32('mapCount')) {
    const { mapBegin, mapEnd, mapCount } = p;
    if (mapBegin < mapEnd && mapEnd <= mapCount && mapCount === fieldMapCount) {
      return { mapBegin, mapEnd, mapCount, maps: mapEnd - mapBegin };
    }
  }
  return { mapBegin: null, mapEnd: null, mapCount: fieldMapCount, maps: null };
}
