// errors.js - validation IDs (spec/validation.md) and the error value the decoder throws.
//
// Every problem a file can have is reported as a VffError carrying the stable numeric ID of
// spec/validation.md, its kebab-case name, the section's FourCC (or '') and the absolute file offset
// where it was found (or -1), so a caller can print `file@0xOFFSET [SECTION]: name (ID): message`.

/** The names of the validation IDs, from spec/validation.md. */
export const CODE_NAMES = Object.freeze({
  2001: 'too-small', 2002: 'bad-magic', 2003: 'unsupported-version', 2004: 'unknown-incompat-feature',
  3001: 'header-size', 3002: 'file-size-mismatch', 3003: 'header-reserved', 3004: 'checksum-algorithm',
  3005: 'header-checksum', 3006: 'section-table', 3007: 'section-count', 3008: 'ro-compat-feature',
  4001: 'section-bounds', 4002: 'section-alignment', 4003: 'section-order',
  4004: 'unknown-required-section', 4005: 'duplicate-section', 4006: 'missing-section',
  4007: 'section-codec', 4008: 'section-checksum', 4009: 'section-reserved', 4010: 'section-size',
  4011: 'section-decode', 4012: 'padding', 4013: 'section-version', 4014: 'section-limit',
  5001: 'sphere', 5002: 'position-scheme', 5003: 'map-count', 5004: 'direction-scheme',
  5005: 'map-resolution', 5006: 'frame-convention', 5007: 'distance-encoding', 5008: 'miss-code',
  5009: 'normal-encoding', 5010: 'field-reserved', 5011: 'decoded-limit',
  6001: 'plane-header', 6002: 'plane-presence', 6003: 'block-bounds', 6004: 'block-alignment',
  6005: 'block-order', 6006: 'block-raw-size', 6007: 'block-codec', 6008: 'block-filter',
  6009: 'block-checksum', 6010: 'block-decode', 6011: 'block-reserved', 6012: 'feature-bit',
  6013: 'value-range',
  7001: 'layout-target', 7002: 'layout-tile', 7003: 'layout-geometry', 7004: 'layout-reserved',
  8001: 'metadata-json', 8002: 'metadata-not-object',
  9001: 'invalid-argument', 9002: 'out-of-range', 9005: 'unsupported',
});

/** A problem of a file (IDs 2xxx-8xxx) or of a call (9xxx). */
export class VffError extends Error {
  /**
   * @param {number} id validation ID
   * @param {string} message what is wrong, in words
   * @param {{section?: string, offset?: number}} [where]
   */
  constructor(id, message, where = {}) {
    const name = CODE_NAMES[id] ?? 'unknown';
    const offset = where.offset ?? -1;
    const section = where.section ?? '';
    const at = (offset >= 0 ? `@0x${offset.toString(16)}` : '') + (section ? ` [${section}]` : '');
    super(`${at ? at.trim() + ': ' : ''}${name} (${id}): ${message}`);
    this.name = 'VffError';
    this.id = id;
    this.codeName = name;
    this.section = section;
    this.offset = offset;
    this.detail = message;
  }
}

/** Throws VffError(id, ...) unless cond holds. */
export function require(cond, id, message, where) {
  if (!cond) throw new VffError(id, message, where);
}
