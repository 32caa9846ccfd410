# declarations.awk - what C++ headers in the style of libvff/include/vff declare (tests/abi):
# "F vff::Class::name" for each function declared and not defined inline (constructors,
# destructors and operators included), "C vff::Class" for each class or struct.
#
# Input: the headers without comments, preprocessor lines, string and character literals
# (abi_tests.sh removes them first). A small parser of the headers' own style: namespaces, classes
# and structs (template ones are header-only and skipped), declarations that end in ";", and
# bodies in braces, which are inline and skipped, as are enumerations and initialisers.
function trim(s) { sub(/^[ \t]+/, "", s); sub(/[ \t]+$/, "", s); return s }
function prefix() { return depth > 0 ? scope[depth] : "" }
function qualify(n) { return prefix() == "" ? n : prefix() "::" n }
# The "(" of a parameter list: the first outside template arguments (std::function<void(int)>).
function parameters(s,    i, c, angles) {
  for (i = 1; i <= length(s); ++i) {
    c = substr(s, i, 1)
    if (c == "<") ++angles
    else if (c == ">") --angles
    else if (c == "(" && angles == 0) return i
  }
  return 0
}
# A declaration ending in ";": a function when it has a parameter list and no initialiser.
function declaration(s,    p, head, name) {
  if (depth > 0 && kind[depth] == "skip") return
  gsub(/(public|private|protected)[ \t]*:( |$)/, " ", s)
  s = trim(s)
  if (s ~ /^(typedef|using|static_assert|friend|template|return)[^A-Za-z0-9_]/) return
  if (s ~ /VFF_HIDDEN/) return  # the library's own, not exported
  if (s ~ /=[ \t]*(default|delete)$/ || s ~ /=[ \t]*0$/) return
  p = parameters(s)
  if (p == 0) return
  head = trim(substr(s, 1, p - 1))
  if (head ~ /(^|[^A-Za-z0-9_])(inline|constexpr)[^A-Za-z0-9_]/) return
  if (head ~ /operator[ \t]*[^ \t]*$/) {
    name = head; sub(/.*operator/, "operator", name); gsub(/[ \t]/, "", name)
  } else {
    if (index(head, "=") > 0) return  # a variable with an initialiser
    if (substr(s, p + 1) ~ /^[ \t]*[*&]/) return  # a pointer to a function: void (*f)(int)
    if (!match(head, /~?[A-Za-z_][A-Za-z0-9_]*$/)) return
    name = substr(head, RSTART, RLENGTH)
  }
  print "F " qualify(name)
}
# The scope a "{" opens.
function open_scope(s,    name) {
  s = trim(s)
  gsub(/(public|private|protected)[ \t]*:( |$)/, " ", s)
  s = trim(s)
  ++depth
  if (depth > 1 && kind[depth - 1] == "skip") { kind[depth] = "skip"; return }
  if (s ~ /^namespace[ \t]/) {
    name = s; sub(/^namespace[ \t]+/, "", name); name = trim(name)
    kind[depth] = "ns"; scope[depth] = (depth > 1 && scope[depth - 1] != "") ? scope[depth - 1] "::" name : name
    return
  }
  if (s ~ /^(class|struct|union)[ \t]/) {
    gsub(/\[\[[^]]*\]\]/, " ", s); gsub(/alignas[ \t]*\([^)]*\)/, " ", s); gsub(/VFF_[A-Z_]+/, " ", s)
    sub(/^(class|struct|union)[ \t]+/, "", s); sub(/[ \t]*:.*$/, "", s)
    name = trim(s); sub(/[ \t].*$/, "", name)
    kind[depth] = "class"; scope[depth] = qualify_at(depth - 1, name)
    print "C " scope[depth]
    return
  }
  kind[depth] = "skip"  # a template, an enum, an inline body, an initialiser
}
function qualify_at(d, n) { return (d > 0 && scope[d] != "") ? scope[d] "::" n : n }
{
  line = $0
  for (i = 1; i <= length(line); ++i) {
    c = substr(line, i, 1)
    if (c == "(") ++parens
    else if (c == ")") --parens
    if (parens == 0 && c == "{") { open_scope(stmt); stmt = ""; continue }
    if (parens == 0 && c == "}") { if (depth > 0) --depth; stmt = ""; continue }
    if (parens == 0 && c == ";") { declaration(stmt); stmt = ""; continue }
    stmt = stmt c
  }
  stmt = stmt " "
}
