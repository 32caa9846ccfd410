// problems.js - every problem of a .vff, not only the first: the reader's checks stop at the first
// structural problem (nothing after it can be read), but the checks of blocks, padding and normals
// (validation.md section 9) are independent and each one that fails is listed.
import { VffError } from '../errors.js';
import { verifyBlock } from '../container.js';

/** A VffError (or any exception) as a plain problem record. */
export function problemOf(e, severity = 'error') {
  if (e instanceof VffError || e?.name === 'VffError')
    return { severity, id: e.id, codeName: e.codeName, section: e.section, offset: e.offset, message: e.message };
  return { severity, id: 0, codeName: 'exception', section: '', offset: -1, message: String(e?.message ?? e) };
}

/** The words of a problem as the page lists it: "NAME: ID-NAME (ID): message". */
export function problemText(name, p) {
  return `${name}: ${p.severity === 'warning' ? 'warning: ' : ''}${p.message}`;
}

/**
 * Runs the checks validateDeep runs, collecting each failure instead of throwing the first.
 * The file must be opened with checksums 'lazy' so that each block's checksum is checked here.
 * onStep(done, total) reports progress. At most `limit` problems of one kind are kept.
 */
export function collectProblems(file, onStep = () => {}, limit = 50) {
  const problems = file.warnings.map((w) => problemOf(w, 'warning'));
  try { file.checkPadding(); } catch (e) { problems.push(problemOf(e)); }
  const planes = Object.keys(file.planes);
  const total = planes.reduce((a, n) => a + file.planes[n].blockCount, 0) + (file.planes.normal ? file.field.mapCount : 0);
  let done = 0, blockProblems = 0;
  const badBlocks = new Set();
  for (const name of planes) {
    const p = file.planes[name];
    for (let b = 0; b < p.blockCount; ++b) {
      try {
        verifyBlock(file.reader, p.blocks[b], p.tag, b);
        file.block(name, b);
      } catch (e) {
        badBlocks.add(`${name}:${b}`);
        if (++blockProblems <= limit) problems.push(problemOf(e));
      }
      onStep(++done, total);
    }
  }
  if (blockProblems > limit) problems.push({ severity: 'error', id: 0, codeName: 'more', section: '', offset: -1, message: `and ${blockProblems - limit} more block problems` });
  if (file.planes.normal) {
    const fd = file.field, G = (n) => file.planes[n].mapsPerBlock;
    const miss = fd.distanceEncoding === 4 ? 0 : fd.missCode;
    let normalProblems = 0;
    for (let k = 0; k < fd.mapCount; ++k, onStep(++done, total)) {
      if (badBlocks.has(`distance:${Math.floor(k / G('distance'))}`) || badBlocks.has(`normal:${Math.floor(k / G('normal'))}`)) continue;
      const c = file.codes(k), nb = file.mapBytes('normal', k);
      let bad = 0, first = -1;
      for (let t = 0; t < c.length; ++t)
        if (c[t] === miss && (nb[4 * t] | nb[4 * t + 1] | nb[4 * t + 2] | nb[4 * t + 3])) { ++bad; if (first < 0) first = t; }
      if (bad && ++normalProblems <= limit)
        problems.push(problemOf(new VffError(6013, `map ${k}: ${bad} misses with a non-zero normal (first: texel ${first})`, { section: 'NORM' })));
    }
    if (normalProblems > limit) problems.push({ severity: 'error', id: 0, codeName: 'more', section: '', offset: -1, message: `and ${normalProblems - limit} more maps with normals on misses` });
  }
  return problems;
}
