// subdivide.h - the same object at other triangle counts, through OpenMesh: Loop subdivision
// (LoopT: four times the triangles per step) and quadric decimation (DecimaterT + ModQuadricT),
// for the benchmark of time per ray against triangle count.
#pragma once

#include <cstdint>

#include "vff/bake/mesh.h"
#include "vff/error.h"

namespace vffx {

// One step of Loop subdivision. Triangles OpenMesh cannot add to a manifold mesh (a complex edge
// or vertex) are left out, and `*dropped` (when given) counts them. Errors: kInvalidArgument when
// no triangle could be added.
vff::Result<vff::bake::Mesh> loopSubdivide(const vff::bake::Mesh& mesh, uint64_t* dropped = nullptr);

// Edge collapses of least quadric error until the mesh has at most `triangles` triangles (or no
// collapse is left). Triangles left out as for loopSubdivide.
vff::Result<vff::bake::Mesh> decimate(const vff::bake::Mesh& mesh, size_t triangles, uint64_t* dropped = nullptr);

}  // namespace vffx
