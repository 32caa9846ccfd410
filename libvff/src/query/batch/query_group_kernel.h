// query_group_kernel.h - the group kernel of query_group.h, written once for any SIMD width.
//
// Included by query_group_sse2.cpp (four-lane vectors), query_group_avx2.cpp (eight-lane vectors)
// and query_group_avx512.cpp (sixteen-lane vectors), each compiled for its instruction set and
// called only where the CPU has it (cpu_features.h). Everything in the kernel's headers sits in an
// anonymous namespace, so each of those files gets its own copy compiled for its own instruction
// set, and no function compiled for AVX2 or AVX-512 can be shared with code that runs on a CPU
// without it (tests/hygiene checks their objects define no weak symbol).
//
// The kernel, one concept to a header:
//   simd/vfloat*_*.h        the lane type H of each instruction set (included by its .cpp first)
//   kernel_lanes.h          Pair<H>: two lane vectors taken as one twice as wide, and lane helpers
//   kernel_math.h           the lookup's maths per lane (frame, hemisphere-to-square, normals)
//   kernel_nearest.h        the sphere step, the nearest sample and texel, the hit decode
//   kernel_interpolated.h   the interpolated planner and blend
//
// The vector type H (a float vector with +, -, *, / and the free functions used below, and static
// load, loadInt, gatherBytes, compressIndex and hitsByRay; AVX2 and AVX-512: gatherSnorm16Pairs)
// and its mask type H::Mask (what comparisons give: band, bor, bandnot, bnot, sel and movemask take
// it; the vector itself, all-ones or zero per lane, in SSE2 and AVX2; a mask register in AVX-512,
// which takes fewer instructions than vector masks) are defined by the including file, which runs
// the kernel on lanes F = Pair<H> or Pair<Pair<H>> (the interpolated planner and blend, planWith
// and blendWith, on H itself, AVX2 and AVX-512 only): two or four vectors side by side, so that
// the CPU overlaps their long dependency chains (the nearest sample, then the frame, then the
// texel). Each file's lane count is the one that ran best on vff-experiments bench (the commit
// history has the figures).
// Every line that computes a quantity prepare() also computes mirrors a line
// of FieldQuery::Impl::prepare() or of fast_lookup.h with the same binary32 operations in the
// same order (a ? b : c becomes sel(mask, b, c); no operation is fused or reordered), so that a
// lane computes bit for bit what prepare() computes for that ray. The one quantity of its own, a
// candidate's score, uses the CPU's approximate reciprocal square root, which differs between
// CPU makers and between rsqrtps and AVX-512's rsqrt14ps: it only decides which sample wins when
// the lead is beyond its error bound (closer leads are settled by the reference's own scores), so
// the answers are the same everywhere, and only which lanes are settled that way can differ.
#pragma once

#include "query/batch/kernel_lanes.h"
#include "query/batch/kernel_math.h"
#include "query/batch/kernel_nearest.h"
#include "query/batch/kernel_interpolated.h"
