// types.mjs - GLSL types as gen-wgsl.mjs tracks them, their WGSL spelling, the WGSL reserved words
// and the helper functions that stand in for GLSL builtins WGSL lacks.
import { fail } from './front.mjs';

export const SCALAR = { float: 'f32', int: 'i32', uint: 'u32', bool: 'bool' };
// GLSL sampler -> [WGSL texture type, sampled scalar, array texture]
export const TEXTURES = {
  sampler2DArray: ['texture_2d_array<f32>', 'float', true],
  usampler2DArray: ['texture_2d_array<u32>', 'uint', true],
  isampler2DArray: ['texture_2d_array<i32>', 'int', true],
  sampler3D: ['texture_3d<f32>', 'float', false],
  usampler3D: ['texture_3d<u32>', 'uint', false],
  isampler3D: ['texture_3d<i32>', 'int', false],
};

export const BOOL = { b: 'bool', n: 1 };
export const INT = { b: 'int', n: 1 };
export const UINT = { b: 'uint', n: 1 };
export const FLOAT = { b: 'float', n: 1 };

/** The type named `name` (a GLSL type or a declared struct), an array when `size` is not undefined. */
export function typeOf(name, size, structs, at) {
  let t;
  const v = /^([iub]?)vec([234])$/.exec(name);
  if (SCALAR[name]) t = { b: name, n: 1 };
  else if (v) t = { b: { '': 'float', i: 'int', u: 'uint', b: 'bool' }[v[1]], n: +v[2] };
  else if (name === 'mat3') t = { mat: 3 };
  else if (TEXTURES[name]) t = { tex: name };
  else if (name === 'void') t = { void: true };
  else if (structs.has(name)) t = { st: name };
  else fail(at, `unknown type '${name}'`);
  return size === undefined ? t : { arr: t, size };
}

export const isNum = (t) => !!t.b && t.b !== 'bool';
export const isInt = (t) => t.b === 'int' || t.b === 'uint';

/** A readable GLSL-like name of a type, for messages and comparisons (array sizes as emitted). */
export function glslName(t) {
  if (t.arr) return `${glslName(t.arr)}[${t.sizeText ?? ''}]`;
  if (t.b) return t.n === 1 ? t.b : `${{ float: '', int: 'i', uint: 'u', bool: 'b' }[t.b]}vec${t.n}`;
  if (t.mat) return 'mat3';
  return t.st || t.tex || 'void';
}
export const same = (a, b) => glslName(a) === glslName(b);

/** The WGSL spelling of a type; an array's size is its emitted text (sizeText). */
export function wgslType(t) {
  if (t.arr) return t.sizeText === undefined ? `array<${wgslType(t.arr)}>` : `array<${wgslType(t.arr)}, ${t.sizeText}>`;
  if (t.b) return t.n === 1 ? SCALAR[t.b] : `vec${t.n}<${SCALAR[t.b]}>`;
  if (t.mat) return 'mat3x3<f32>';
  if (t.tex) return TEXTURES[t.tex][0];
  if (t.st) return t.st;
  return 'void';
}

// WGSL keywords and reserved words (WGSL specification, "Keyword Summary" and "Reserved Words"), and
// the predeclared names the generated code calls or spells, so that no local shadows them.
export const RESERVED = new Set(`alias break case const const_assert continue continuing default diagnostic discard
else enable false fn for if let loop override requires return struct switch true var while
NULL Self abstract active alignas alignof as asm asm_fragment async attribute auto await become binding_array cast
catch class co_await co_return co_yield coherent column_major common compile compile_fragment concept const_cast
consteval constexpr constinit crate debugger decltype delete demote demote_to_helper do dynamic_cast enum explicit
export extends extern external fallthrough filter final finally friend from fxgroup get goto groupshared highp impl
implements import inline instanceof interface layout lowp macro macro_rules match mediump meta mod module move mut
mutable namespace new nil noexcept noinline nointerpolation noperspective null nullptr of operator package packoffset
partition pass patch pixelfragment precise precision premerge priv protected pub public readonly ref regardless
register reinterpret_cast require resource restrict self set shared sizeof smooth snorm static static_assert
static_cast std subroutine super target template this thread_local throw trait try type typedef typeid typename
typeof union unless unorm unsafe unsized use using varying virtual volatile wgsl where with writeonly yield
select bitcast atan2 inverseSqrt textureLoad textureDimensions textureNumLayers arrayLength array ptr atomic
f32 f16 i32 u32 vec2 vec3 vec4 mat2x2 mat3x3 mat4x4 sampler texture_2d_array texture_3d function private storage
uniform workgroup read read_write all any`.split(/\s+/));

// Helpers for GLSL builtins without a WGSL equal, emitted once each where used.
export const HELPERS = {
  isnan: `// GLSL isnan: all exponent bits set and a nonzero mantissa, read from the bits so that a compiler
// assuming finite values cannot fold the test away.
fn glsl_isnan(x: f32) -> bool {
  let b = bitcast<u32>(x);
  return (b & 0x7f800000u) == 0x7f800000u && (b & 0x007fffffu) != 0u;
}`,
  isinf: `// GLSL isinf: all exponent bits set and a zero mantissa (from the bits, as glsl_isnan).
fn glsl_isinf(x: f32) -> bool {
  return (bitcast<u32>(x) & 0x7fffffffu) == 0x7f800000u;
}`,
  umulExtended: `// GLSL umulExtended: the 64-bit product of a and b from 16-bit halves.
fn glsl_umulExtended(a: u32, b: u32, hi: ptr<function, u32>, lo: ptr<function, u32>) {
  let a0 = a & 0xFFFFu;
  let a1 = a >> 16u;
  let b0 = b & 0xFFFFu;
  let b1 = b >> 16u;
  let p01 = a0 * b1;
  let p10 = a1 * b0;
  let mid = ((a0 * b0) >> 16u) + (p01 & 0xFFFFu) + (p10 & 0xFFFFu);
  *hi = a1 * b1 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u);
  *lo = a * b;
}`,
  uintBitsToFloat: `// GLSL uintBitsToFloat of a constant: bitcast<f32> of a constant that is not finite (the
// +inf of a miss) is a shader-creation error in WGSL; through a function it is evaluated at run time.
fn glsl_uintBitsToFloat(x: u32) -> f32 {
  return bitcast<f32>(x);
}`,
};
for (const [name, [wt, b]] of Object.entries(TEXTURES)) {
  if (!TEXTURES[name][2]) continue;
  HELPERS[`texelFetch_${name}`] = `// GLSL texelFetch on ${/^[aeiou]/.test(name) ? 'an' : 'a'} ${name}: the layer is the coordinate's z.
fn glsl_texelFetch_${name}(t: ${wt}, c: vec3<i32>, lod: i32) -> vec4<${SCALAR[b]}> {
  return textureLoad(t, c.xy, c.z, lod);
}`;
}
