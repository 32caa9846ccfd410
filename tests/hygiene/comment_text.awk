# comment_text.awk - prints FILE:LINE:TEXT for the comment text of every line that has some.
#
#   awk -f comment_text.awk FILE...
#
# C-style files (C++, GLSL): the text after // and inside /* */ (a block may span lines); string
# and character literals are skipped, so a "//" inside a literal is no comment. A raw string
# R"(...)" is read as code, line by line: none in the tree holds a "//".
# Hash-style files (CMakeLists.txt, *.cmake, *.sh): the text after a # that starts the line or
# follows a blank.
FNR == 1 {
  inBlock = 0
  hashStyle = FILENAME ~ /(CMakeLists\.txt|\.cmake|\.sh)$/
}
hashStyle {
  if (match($0, /(^|[ \t])#/)) print FILENAME ":" FNR ":" substr($0, RSTART + RLENGTH)
  next
}
{
  line = $0
  text = ""
  n = length(line)
  i = 1
  while (i <= n) {
    c = substr(line, i, 1)
    two = substr(line, i, 2)
    if (inBlock) {
      if (two == "*/") {
        inBlock = 0
        text = text " "
        i += 2
      } else {
        text = text c
        i++
      }
    } else if (two == "//") {
      text = text " " substr(line, i + 2)
      break
    } else if (two == "/*") {
      inBlock = 1
      i += 2
    } else if (c == "\"" || c == "'") {
      for (i++; i <= n && substr(line, i, 1) != c; i++)
        if (substr(line, i, 1) == "\\") i++
      i++
    } else {
      i++
    }
  }
  if (text ~ /[^ \t]/) print FILENAME ":" FNR ":" text
}
