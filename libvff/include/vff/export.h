// vff/export.h - which of libvff's symbols its shared libraries export.
//
// libvff.so and libvff_embree.so are compiled with hidden visibility (CMake's CXX_VISIBILITY_PRESET
// hidden and VISIBILITY_INLINES_HIDDEN, libvff/CMakeLists.txt): a symbol is exported only where a
// public header marks it, so that the library's own steps (everything in libvff/src, namespace
// vff::detail, the opaque Impl structs) stay free to change and cannot be interposed. The marks:
//
//   VFF_API           libvff's API: every class with out-of-line members (`class VFF_API File`) and
//                     every free function the headers declare and do not define inline.
//   VFF_EXPERIMENTAL  the same export, for API that may still change between minor versions:
//                     * Scene::hierarchy() and its flat layout (vff/scene_hierarchy.h), which
//                       follows the GLSL scene walker (gpu/glsl/vff_scene.glsl) as that evolves;
//                     * queryNeighbours() (vff/query.h), kInterpolated's neighbour lists, exported
//                       for a GPU port of the blend and changing with it.
//   VFF_EMBREE_API, VFF_EMBREE_EXPERIMENTAL
//                     the same for the optional component vff::embree (libvff_embree.so,
//                     vff/embree.h), which is experimental as a whole: how a field meets Embree's
//                     user-geometry callbacks is still being measured (vff-experiments scene-bench).
//
// Public inline code (PositionSet::frame, File::hasNormals, the spellings of vff/spelling.h, the
// Result templates) calls only functions marked here: nothing in vff::detail is exported, and a
// public header must not call into it. tests/abi checks the exported symbols against these rules.
//
// Building the libraries defines VFF_BUILDING (libvff) and VFF_EMBREE_BUILDING (vff::embree),
// PRIVATE to their targets. With GCC and Clang the marks give default visibility whether or not
// they are defined (a consumer's declarations then match the library's on ELF); on Windows they
// choose dllexport or dllimport; other compilers get nothing.
#pragma once

#if defined(_WIN32) || defined(__CYGWIN__)
#if defined(VFF_BUILDING)
#define VFF_API __declspec(dllexport)
#else
#define VFF_API __declspec(dllimport)
#endif
#if defined(VFF_EMBREE_BUILDING)
#define VFF_EMBREE_API __declspec(dllexport)
#else
#define VFF_EMBREE_API __declspec(dllimport)
#endif
#define VFF_HIDDEN
#elif defined(__GNUC__) || defined(__clang__)
#define VFF_API __attribute__((visibility("default")))
#define VFF_EMBREE_API __attribute__((visibility("default")))
// For the library's own use: the opaque structs nested in exported classes (File::Impl,
// FieldQuery::Impl, ...), whose members would otherwise take the class's default visibility, and
// the members of an exported class that only the library calls (File's constructor from an Impl).
#define VFF_HIDDEN __attribute__((visibility("hidden")))
#else
#define VFF_API
#define VFF_EMBREE_API
#define VFF_HIDDEN
#endif

#define VFF_EXPERIMENTAL VFF_API
#define VFF_EMBREE_EXPERIMENTAL VFF_EMBREE_API
