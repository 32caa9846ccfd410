#!/usr/bin/env bash
# abi_tests.sh - the symbols libvff.so and libvff_embree.so export are their public API's, all of
# it and nothing else (vff/export.h; label abi).
#
# Every function named test_* is one ctest case (tests/abi/CMakeLists.txt); environment:
#   NM              the toolchain's nm (GNU or LLVM: -D, --defined-only, -C)
#   VFF_LIB         libvff.so
#   VFF_EMBREE_LIB  libvff_embree.so, or empty where the component is not built
#   VFF_HEADERS     the public headers, libvff/include/vff
#   WORK            a scratch folder of this test.
#
# The rules, for each library:
# (a) Every exported symbol is in namespace vff: its functions, and the typeinfo, vtables and guard
#     variables of its types. Nothing of the standard library's: the instantiations, typeinfo and
#     static locals that the compiler emits with default visibility whatever -fvisibility says
#     (libstdc++ declares namespace std so) are hidden by the linker's list, libvff/exports.map,
#     since they are no API and some are over the library's own lambdas. Nor C names.
# (b) Nothing internal: no exported symbol names vff::detail, an Impl or State struct (the opaque
#     parts of exported classes), an anonymous namespace or a lambda; and every exported function
#     of namespace vff is one that a public header declares (so no function defined only in
#     libvff/src is exported, whatever its namespace).
# (c) The whole API: every function the public headers declare and do not define inline (those
#     VFF_API, VFF_EXPERIMENTAL or inside a class so marked) is exported, among them a few named
#     below, so that a parser that found nothing cannot pass.
#
# The headers are read by declarations.awk, a small parser of their own style.
set -euo pipefail
: "${NM:?}" "${VFF_LIB:?}" "${VFF_HEADERS:?}" "${WORK:?}"
VFF_EMBREE_LIB="${VFF_EMBREE_LIB:-}"
export LC_ALL=C  # (sort and comm alike)
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
source "$here/../common/cli_harness.sh"

# Functions that must be exported whatever the parser finds (rule c).
kSampledLibvff=(vff::File::open vff::File::mapData vff::FieldQuery::fromFile vff::FieldQuery::intersect
  vff::Instance::occluded vff::Scene::commit vff::Writer::create vff::validateFile vff::loadScene
  vff::Error::toString vff::positionCount vff::Scene::hierarchy vff::queryNeighbours)
kSampledEmbree=(vff::embree::FieldGeometry::attach vff::embree::FieldGeometry::setTransform)
# Exported names that are internal wherever they appear (rule b): an extended regular expression.
kInternal='vff::detail::|::Impl([^A-Za-z0-9_]|$)|::State([^A-Za-z0-9_]|$)|anonymous namespace|\{anonymous\}|\{lambda'

# The libraries built here, as "name path" lines.
libraries() {
  echo "libvff $VFF_LIB"
  if [[ -n $VFF_EMBREE_LIB ]]; then
    echo "libvff_embree $VFF_EMBREE_LIB"
  else
    echo "abi: vff_embree is not built: only libvff is checked" >&2
  fi
}

# The public headers of a library, one a line.
headers_of() {
  case "$1" in
    libvff) find "$VFF_HEADERS" -maxdepth 1 -name '*.h' ! -name embree.h | sort ;;
    libvff_embree) echo "$VFF_HEADERS/embree.h" ;;
  esac
}

# The exported (dynamic, defined) symbols of a library, demangled: "TYPE NAME" a line, with the
# ABI tags ([abi:cxx11]) left out.
exports() {
  "$NM" -D --defined-only -C "$1" | awk '{ $1 = ""; sub(/^ +/, ""); gsub(/\[abi:[A-Za-z0-9_]+\]/, ""); print }'
}

# What a symbol is about: its name without "typeinfo for " and the like.
strip_kind() {
  sed -E 's/^(typeinfo name for|typeinfo for|vtable for|VTT for|construction vtable for|guard variable for) //'
}

# What the headers declare: "F vff::Class::name" for each function declared and not defined inline
# (constructors, destructors and operators included), "C vff::Class" for each class or struct
# (declarations.awk).
public_declarations() {
  # Comments, preprocessor lines, then string and character literals go first.
  sed -E -e 's://.*$::' -e '/^[[:space:]]*#/d' -e 's/"([^"\\]|\\.)*"/""/g' -e "s/'([^'\\\\]|\\\\.)*'/''/g" "$@" |
    awk -f "$here/declarations.awk"
}

# ---- (a) ------------------------------------------------------------------------------------------
test_exports_are_in_namespace_vff() {
  local name lib bad checked=0
  while read -r name lib; do
    exports "$lib" >"$WORK/$name.exports"
    bad=$(cut -d' ' -f2- "$WORK/$name.exports" | strip_kind | grep -v '^vff::' || true)
    [[ -z $bad ]] || fail "$name exports symbols outside namespace vff (rule a, tests/abi/abi_tests.sh):
$bad"
    checked=$((checked + $(wc -l <"$WORK/$name.exports")))
  done < <(libraries)
  ((checked > 0)) || fail "no exported symbol found in $VFF_LIB"
  echo "checked $checked exported symbols"
}

# ---- (b) ------------------------------------------------------------------------------------------
test_no_internal_symbol_is_exported() {
  local name lib bad
  while read -r name lib; do
    bad=$(exports "$lib" | grep -E -e "$kInternal" || true)
    [[ -z $bad ]] || fail "$name exports internal symbols (rule b):
$bad"
  done < <(libraries)
}

test_every_exported_function_is_declared_in_a_public_header() {
  local name lib bad
  while read -r name lib; do
    headers_of "$name" | xargs cat >"$WORK/$name.h"
    public_declarations "$WORK/$name.h" | sort -u >"$WORK/$name.declared"
    # Exported functions of namespace vff, by qualified name; typeinfo and vtables by their class.
    exports "$lib" | cut -d' ' -f2- | grep -E '^((typeinfo name|typeinfo|vtable|VTT) for )?vff::' |
      sed -E -e 's/^(typeinfo name|typeinfo|vtable|VTT) for (.*)$/C \2/' -e '/^C /!s/^([^(]*)\(.*$/F \1/' |
      sort -u >"$WORK/$name.exported"
    bad=$(comm -23 "$WORK/$name.exported" "$WORK/$name.declared")
    [[ -z $bad ]] || fail "$name exports what no public header of it declares (rule b; F: function, C: class):
$bad"
    echo "$name: $(wc -l <"$WORK/$name.exported") exported names, each declared"
  done < <(libraries)
}

# ---- (c) ------------------------------------------------------------------------------------------
test_every_declared_function_is_exported() {
  local name lib bad f
  while read -r name lib; do
    headers_of "$name" | xargs cat >"$WORK/$name.h"
    public_declarations "$WORK/$name.h" | grep '^F ' | sort -u >"$WORK/$name.declared"
    exports "$lib" | cut -d' ' -f2- | grep -E '^vff::' | sed -E 's/^([^(]*)\(.*$/F \1/' | sort -u >"$WORK/$name.exported"
    bad=$(comm -23 "$WORK/$name.declared" "$WORK/$name.exported")
    [[ -z $bad ]] || fail "$name does not export functions its public headers declare (rule c: mark them VFF_API):
$bad"
    local -a sampled=("${kSampledLibvff[@]}")
    [[ $name == libvff ]] || sampled=("${kSampledEmbree[@]}")
    for f in "${sampled[@]}"; do
      grep -q -x -F "F $f" "$WORK/$name.declared" || fail "$name: the parser did not find $f in the headers"
      grep -q -x -F "F $f" "$WORK/$name.exported" || fail "$name does not export $f"
    done
    echo "$name: $(wc -l <"$WORK/$name.declared") declared functions, each exported"
  done < <(libraries)
}

# The parser itself, on a header that has each form it must tell apart.
test_declaration_parser_reads_each_form() {
  cat >"$WORK/h.h" <<'EOF'
// a comment with a brace { and a (paren);
#pragma once
#include "vff/export.h"
namespace vff {
inline constexpr uint32_t kTag = fourcc('{', 'D', 'S', ';');
inline constexpr uint64_t kNoOffset = ~uint64_t{0};
enum class Code : uint32_t { kOk = 0, kBad = 1 };
VFF_API const char* codeName(Code code) noexcept;  // "ok"
VFF_API Status writeFile(const std::string& path, std::span<const uint8_t> normals = {},
                         const WriteOptions& options = {});
constexpr uint32_t fourcc(char a) { return uint32_t(a); }
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}
  bool ok() const noexcept;
};
struct Plain {
  float t = std::numeric_limits<float>::infinity();
  std::function<void(uint64_t done, uint64_t total)> progress;
  uint64_t maxMaps = uint64_t{1} << 24;
  std::array<float, 4> rotation{0, 0, 0, 1};
  void (*callback)(int) = nullptr;
};
class VFF_API File {
 public:
  static Result<File> open(const std::string& path, const ReadOptions& options = {});
  File(File&&) noexcept;
  File& operator=(File&&) noexcept;
  ~File();
  File() = default;
  VFF_HIDDEN explicit File(std::unique_ptr<Impl> impl);  // used by the library only
  bool hasNormals() const noexcept { return plane(Plane::kNormal).present; }
  struct Impl;
  friend struct Instance;
  VFF_EXPERIMENTAL Result<int> hierarchy() const;
 private:
  static Vec3 negate(Vec3 v) noexcept { return {-v.x, -v.y, -v.z}; }
  std::unique_ptr<Impl> impl_;
};
}  // namespace vff
namespace vff::embree {
class VFF_EMBREE_API FieldGeometry {
 public:
  unsigned geomID() const noexcept;
};
}  // namespace vff::embree
EOF
  public_declarations "$WORK/h.h" >"$WORK/got"
  cat >"$WORK/want" <<'EOF'
F vff::codeName
F vff::writeFile
C vff::Plain
C vff::File
F vff::File::open
F vff::File::File
F vff::File::operator=
F vff::File::~File
F vff::File::hierarchy
C vff::embree::FieldGeometry
F vff::embree::FieldGeometry::geomID
EOF
  diff -u "$WORK/want" "$WORK/got" || fail "the declaration parser misreads the sample header"
}

run_test "$1"
