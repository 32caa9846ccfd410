#!/usr/bin/env python3
"""include_graph.py - checks that the folders use only the floors below them (CONTRIBUTING.md,
"Where things live"), on the source files themselves (no build needed).

    python3 include_graph.py ROOT

Prints every arrow that breaks a rule as FILE:LINE: message (relative to ROOT), then
"checked N arrows in M files"; exits 1 when it printed a broken arrow. The arrows:
  * every #include "..." of a C++ or GLSL file, resolved as the compiler does (relative to the
    file, then the include roots of INCLUDE_ROOTS, then any file of the tree the path names);
    <...> includes and headers outside the tree (system and third-party ones) are no arrow;
  * every path of a CMake file that leaves its folder (../, ${PROJECT_SOURCE_DIR}/...): a source
    file it compiles, a folder it adds to the include path or as a subdirectory.
The rules:
  * no arrow from a lower floor to a higher one (FLOORS);
  * no tool (tools/vff-*) includes or compiles a file of another tools/ folder but the shared
    libraries (tools/common, tools/bake-job, tools/interchange), which it links; and none compiles
    their sources;
  * no CMake file outside tests/ compiles a file under tests/ (no product target is built from a
    test's sources).
"""
import os
import re
import sys

# Folder (path prefix, most specific first) -> floor. CONTRIBUTING.md's table; spec/ has no floor
# there: its conformance generator is a program on libvff, so it sits with the programs (3).
FLOORS = [
    ("libvff/", 0),
    ("bake/", 1),
    ("gpu/loader/", 1),
    ("gpu/glsl/", 1),
    ("gpu/harness/", 2),
    ("gpu/sdf/", 2),
    ("gpu/", 1),
    ("sdf/", 2),
    ("tools/", 3),
    ("python/", 3),
    ("web/", 3),
    ("spec/", 3),
    ("samples/", 4),
    ("benchmarks/", 4),
    ("tests/", 5),
]
# Include prefix -> the folder the compiler finds it in (the public headers' roots).
INCLUDE_ROOTS = [
    ("vff/bake/", "bake/include/"),
    ("vff/sdf/", "sdf/include/"),
    ("vff/gl/", "gpu/loader/include/"),
    ("vff/", "libvff/include/"),
]
# What tools/vff-* may use of the other tools/ folders: their headers (it links their library).
TOOL_LIBRARIES = ("tools/common/", "tools/bake-job/", "tools/interchange/")

SOURCE_EXTENSIONS = (".cpp", ".cc", ".c", ".h", ".hpp", ".inl", ".glsl", ".comp")
SKIP_FOLDERS = {"node_modules", ".git", "__pycache__"}
INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


def floor_of(path):
    """(folder, floor) of a path relative to the root, or None for one on no floor."""
    for prefix, floor in FLOORS:
        if path.startswith(prefix):
            return prefix.rstrip("/"), floor
    return None


def tool_of(path):
    """The tools/ folder of a path ("tools/vff-query"), or None."""
    parts = path.split("/")
    return "/".join(parts[:2]) if len(parts) > 2 and parts[0] == "tools" else None


def walk(root):
    """Every file under the floors' folders (and the root's CMake files), relative to root."""
    files = [name for name in ("CMakeLists.txt",) if os.path.isfile(os.path.join(root, name))]
    tops = sorted({prefix.split("/")[0] for prefix, _ in FLOORS} | {"cmake"})
    for top in tops:
        for folder, dirs, names in os.walk(os.path.join(root, top)):
            dirs[:] = sorted(d for d in dirs if d not in SKIP_FOLDERS)
            for name in sorted(names):
                files.append(os.path.relpath(os.path.join(folder, name), root))
    return files


class Tree:
    def __init__(self, root):
        self.root = root
        self.files = walk(root)
        self.known = set(self.files)
        self.by_name = {}
        for f in self.files:
            self.by_name.setdefault(os.path.basename(f), []).append(f)

    def exists(self, rel):
        return rel in self.known

    def resolve_include(self, includer, name):
        """The file `includer` includes as "name", or None (outside the tree), or a list (ambiguous)."""
        rel = os.path.normpath(os.path.join(os.path.dirname(includer), name))
        if self.exists(rel):
            return rel
        for prefix, folder in INCLUDE_ROOTS:
            if name.startswith(prefix):
                rel = os.path.normpath(folder + name)
                if self.exists(rel):
                    return rel
                break
        # Another include root (a library's own folder, libvff/src for its private headers, tests/
        # for tests/common): the files whose path ends with the name.
        suffix = "/" + os.path.normpath(name)
        found = [f for f in self.by_name.get(os.path.basename(name), []) if ("/" + f).endswith(suffix)]
        if len(found) > 1:  # the includer's own folder first
            own = floor_of(includer)
            mine = [f for f in found if own and floor_of(f) == own]
            found = mine if len(mine) == 1 else found
        if not found:
            return None
        return found[0] if len(found) == 1 else found


def includes(tree, path):
    """(line, target) of every #include "..." of a source file; target as resolve_include."""
    with open(os.path.join(tree.root, path), encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            m = INCLUDE_RE.match(line)
            if m:
                yield number, m.group(1), tree.resolve_include(path, m.group(1))


CMAKE_ROOT_VARS = ("PROJECT_SOURCE_DIR", "CMAKE_SOURCE_DIR", "vff_SOURCE_DIR")
CMAKE_HERE_VARS = ("CMAKE_CURRENT_SOURCE_DIR", "CMAKE_CURRENT_LIST_DIR")
CMAKE_COMMAND_RE = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*\(")


def cmake_paths(tree, path):
    """(line, command, target, is_source) of every path of a CMake file that leaves its folder and
    names a file or folder of the tree."""
    here = os.path.dirname(path)
    command = ""
    with open(os.path.join(tree.root, path), encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            line = re.sub(r'(^|\s)#.*$', "", line)  # comments (a # that starts a word)
            for m in CMAKE_COMMAND_RE.finditer(line):
                command = m.group(1).lower()
            for token in re.split(r'[\s()"]+', line):
                if not token:
                    continue
                leaves = ".." in token.split("/")
                for var in CMAKE_ROOT_VARS:
                    if token.startswith("${%s}" % var):
                        token, leaves = token[len(var) + 3:].lstrip("/"), True
                        break
                else:
                    for var in CMAKE_HERE_VARS:
                        if token.startswith("${%s}" % var):
                            token = os.path.join(here, token[len(var) + 3:].lstrip("/"))
                            break
                    else:
                        token = os.path.join(here, token)
                if not leaves or "${" in token or "$<" in token:
                    continue
                rel = os.path.normpath(token)
                if rel.startswith(".."):
                    continue  # outside the tree (../shared/meshes)
                if tree.exists(rel):
                    yield number, command, rel, rel.endswith(SOURCE_EXTENSIONS)
                elif os.path.isdir(os.path.join(tree.root, rel)) and command in (
                        "add_subdirectory", "target_include_directories", "include_directories"):
                    yield number, command, rel + "/", False


def check_arrow(source, target, what):
    """The rule `source` -> `target` breaks, or None."""
    a, b = floor_of(source), floor_of(target)
    if a and b and b[1] > a[1]:
        return "%s %s: %s (floor %d) uses %s (floor %d)" % (what, target, a[0], a[1], b[0], b[1])
    ta, tb = tool_of(source), tool_of(target)
    if ta and tb and ta != tb and ta.startswith("tools/vff-") and not target.startswith(TOOL_LIBRARIES):
        return "%s %s: a tool uses another tool's files (%s -> %s)" % (what, target, ta, tb)
    return None


def main(root):
    tree = Tree(root)
    broken = arrows = files = 0

    def report(path, line, message):
        nonlocal broken
        print("%s:%d: %s" % (path, line, message))
        broken += 1

    for path in tree.files:
        if path.endswith(SOURCE_EXTENSIONS):
            files += 1
            for line, name, target in includes(tree, path):
                if target is None:
                    continue
                if isinstance(target, list):
                    report(path, line, '#include "%s" names several files (%s): give its folder' %
                           (name, ", ".join(target)))
                    continue
                arrows += 1
                message = check_arrow(path, target, '#include "%s" ->' % name)
                if message:
                    report(path, line, message)
        elif os.path.basename(path) == "CMakeLists.txt" or path.endswith(".cmake"):
            files += 1
            for line, command, target, is_source in cmake_paths(tree, path):
                arrows += 1
                message = check_arrow(path, target, "%s(... %s)" % (command, target.rstrip("/")) + " ->")
                if message:
                    report(path, line, message)
                elif is_source and target.startswith("tests/") and not path.startswith("tests/"):
                    report(path, line, "%s(... %s): a product target compiles a test's file" % (command, target))
                elif (is_source and tool_of(path) and tool_of(path).startswith("tools/vff-")
                      and tool_of(target) and tool_of(target) != tool_of(path)):
                    report(path, line, "%s(... %s): a tool compiles another tools/ folder's source (link its library)" %
                           (command, target))
    print("checked %d arrows in %d files" % (arrows, files))
    if files == 0:
        print("no source file under %s" % root)
        return 1
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "."))
