# tools/man.awk: ray's manual page, ray.1, from the one copy of each text.
#
#     ./ray --help | awk -v version="$(./ray --version)" -v date=YYYY-MM-DD \
#         -v readme=README.md -f tools/man.awk >ray.1
#
# (make builds ray.1 so, with the date of the last commit.)  Only the headings are written here.  NAME,
# SYNOPSIS, DESCRIPTION and each option under OPTIONS are --help's (cli.c
# holds that text once), the version is --version's, and the rest is the
# README's own sentences: DESCRIPTION goes on with its paragraph "Viewing
# the image."; EXIT STATUS is the sentence "The exit status is ..." and
# FILES the paragraph "The image is written to a temporary file ..." under
# "Output and the command line"; EXAMPLES are the sentences that start with
# a command `./ray ...` under "The two commands".  A text not found is an
# error (exit 1, nothing usable written), so the page never quietly loses a
# section.  In the README's text, `code` turns bold, **bold** bold, *this*
# italic, [a link](target) its words (one within the README, in brackets,
# is left out); in every text the dashes of an option name are minus signs,
# which a line never breaks at, and no word is hyphenated (.nh), so that
# every option can be searched for as it is typed.

# s as roff text: backslashes kept, the README's few non-ASCII characters
# as roff names them
function roff(s) {
    gsub(/\\/, "\\e", s)
    gsub(/×/, "\\(mu", s)
    gsub(/–/, "\\(en", s)
    gsub(/—/, "\\(em", s)
    return s
}

# Markdown's emphasis and links in prose (no code in it)
function prose(s,   t) {
    gsub(/ \(\[[^]]*\]\(#[^)]*\)\)/, "", s)
    while (match(s, /\[[^]]*\]\([^)]*\)/)) {
        t = substr(s, RSTART + 1, RLENGTH - 1)
        s = substr(s, 1, RSTART - 1) substr(t, 1, index(t, "]") - 1) substr(s, RSTART + RLENGTH)
    }
    while (match(s, /\*\*[^*]+\*\*/))
        s = substr(s, 1, RSTART - 1) "\\fB" substr(s, RSTART + 2, RLENGTH - 4) "\\fR" substr(s, RSTART + RLENGTH)
    while (match(s, /\*[^* ][^*]*\*/))
        s = substr(s, 1, RSTART - 1) "\\fI" substr(s, RSTART + 1, RLENGTH - 2) "\\fR" substr(s, RSTART + RLENGTH)
    return options(s)
}

# each word that starts (after brackets) with an option's dash: every dash
# in it a minus sign
function options(s,   n, w, i, out) {
    n = split(s, w, / /)
    out = ""
    for (i = 1; i <= n; i++) {
        if (w[i] ~ /^[([]*--?[A-Za-z0-9]/ || w[i] == "-") gsub(/-/, "\\-", w[i])
        out = out (i > 1 ? " " : "") w[i]
    }
    return out
}

# a text with `code` spans: the code bold and its dashes minus signs, the
# rest prose
function text(s,   out, n, code) {
    s = roff(s)
    out = ""
    while ((n = index(s, "`")) > 0 && index(substr(s, n + 1), "`") > 0) {
        out = out prose(substr(s, 1, n - 1))
        s = substr(s, n + 1)
        n = index(s, "`")
        code = substr(s, 1, n - 1)
        gsub(/-/, "\\-", code)
        out = out "\\fB" code "\\fR"
        s = substr(s, n + 1)
    }
    return out prose(s)
}

# roff text s printed in lines of at most 80 bytes, broken at spaces (a
# word longer than that stands alone), no line taken for a request
function put(s,   n, w, i, line) {
    n = split(s, w, / +/)
    line = ""
    for (i = 1; i <= n; i++) {
        if (line != "" && length(line) + 1 + length(w[i]) > 80) { emit(line); line = "" }
        line = line (line == "" ? "" : " ") w[i]
    }
    if (line != "") emit(line)
}
function emit(line) {
    if (line ~ /^[.']/) line = "\\&" line
    print line
}

# the README's paragraph p of section sec
function paragraph(sec, p,   k) {
    if (p == "") return
    k = ++paragraphs
    para[k] = p
    section[k] = sec
}

# the sentences of p into sent[1..n]: a sentence ends at ". " before a
# capital or a backquote
function sentences(p,   n, i, c) {
    n = 0
    while (1) {
        for (i = 1; i < length(p); i++)
            if (substr(p, i, 2) == ". " && substr(p, i + 2, 1) ~ /[A-Z`]/) break
        sent[++n] = substr(p, 1, i)
        if (i >= length(p)) return n
        p = substr(p, i + 2)
    }
}

function missing(what) {
    print "tools/man.awk: " readme " has no " what > "/dev/stderr"
    failed = 1
    exit 1
}

BEGIN {
    if (readme == "") readme = "README.md"
    if (date !~ /^[0-9][0-9][0-9][0-9]-[0-9][0-9]-[0-9][0-9]$/) {
        print "tools/man.awk: -v date=YYYY-MM-DD, not " date > "/dev/stderr"
        failed = 1
        exit 1
    }
    sec = ""
    p = ""
    while ((r = getline line < readme) > 0) {
        if (line ~ /^## /) { paragraph(sec, p); p = ""; sec = substr(line, 4); continue }
        if (line ~ /^$/ || line ~ /^    / || line ~ /^(```|\|)/) { paragraph(sec, p); p = ""; continue }
        p = p (p == "" ? "" : " ") line
    }
    if (r < 0) missing("file")
    close(readme)
    paragraph(sec, p)
    for (k = 1; k <= paragraphs; k++) {
        if (para[k] ~ /^\*\*Viewing the image\.\*\*/) viewing = para[k]
        if (section[k] == "Output and the command line") {
            if (para[k] ~ /^The image is written to a temporary file/) files = para[k]
            n = sentences(para[k])
            for (i = 1; i <= n; i++) if (sent[i] ~ /^The exit status is/) status = sent[i]
        }
        if (section[k] == "The two commands") {
            n = sentences(para[k])
            for (i = 1; i <= n; i++)
                if (match(sent[i], /^`\.\/ray [^`]*`/)) {
                    example_cmd[++examples] = substr(sent[i], 4, RLENGTH - 4)
                    rest = substr(sent[i], RLENGTH + 2)
                    example_text[examples] = toupper(substr(rest, 1, 1)) substr(rest, 2)
                }
        }
    }
    if (viewing == "") missing("paragraph \"**Viewing the image.**\"")
    if (files == "") missing("paragraph \"The image is written to a temporary file\" under \"Output and the command line\"")
    if (status == "") missing("sentence \"The exit status is\" under \"Output and the command line\"")
    if (!examples) missing("sentence starting `./ray ...` under \"The two commands\"")
    split(version, v, " ")
    sub(/,$/, "", v[2])
    nopt = 0
}

# --help: the usage line, the description up to the first option, then the
# options, each "  -x ARG    text" with its text's lines indented further
NR == 1 {
    if ($1 != "usage:") { print "tools/man.awk: not ray --help's text: " $0 > "/dev/stderr"; failed = 1; exit 1 }
    synopsis = "\\fB" $2 "\\fR"
    for (i = 3; i <= NF; i++) {
        w = $i
        if (w ~ /^\[.*\]$/) w = "[\\fI" substr(w, 2, length(w) - 2) "\\fR]"
        else w = "\\fI" w "\\fR"
        synopsis = synopsis " " w
    }
    next
}
/^  -/ {
    line = substr($0, 3)
    n = index(line, "  ")
    head = n ? substr(line, 1, n - 1) : line
    body = n ? substr(line, n) : ""
    sub(/^ +/, "", body)
    k = split(head, h, " ")
    opt_head[++nopt] = "\\fB" options(h[1]) "\\fR"
    for (i = 2; i <= k; i++) opt_head[nopt] = opt_head[nopt] " \\fI" h[i] "\\fR"
    opt_text[nopt] = body
    next
}
/^   / && nopt {
    sub(/^ +/, "")
    opt_text[nopt] = opt_text[nopt] " " $0
    next
}
!nopt { description = description (description == "" ? "" : " ") $0; next }
{ print "tools/man.awk: a line of --help that is no option's: " $0 > "/dev/stderr"; failed = 1; exit 1 }

END {
    if (failed) exit 1
    if (!nopt) { print "tools/man.awk: no options in the --help text" > "/dev/stderr"; exit 1 }
    name = description
    sub(/:.*/, "", name)
    print ".\\\" Made by tools/man.awk from ray --help and README.md: edit those."
    print ".TH RAY 1 \"" date "\" \"" v[1] " " v[2] "\" \"User Commands\""
    print ".nh"
    print ".SH NAME"
    print "ray \\- " text(tolower(substr(name, 1, 1)) substr(name, 2))
    print ".SH SYNOPSIS"
    print synopsis
    print ".SH DESCRIPTION"
    put(text(description))
    print ".PP"
    put(text(viewing))
    print ".SH OPTIONS"
    for (i = 1; i <= nopt; i++) {
        print ".TP"
        print opt_head[i]
        put(text(opt_text[i]))
    }
    print ".SH EXIT STATUS"
    put(text(status))
    print ".SH FILES"
    put(text(files))
    print ".SH EXAMPLES"
    print "The scenes named are in the source's directory scenes/."
    for (i = 1; i <= examples; i++) {
        print ".TP"
        print text("`" example_cmd[i] "`")
        put(text(example_text[i]))
    }
}
