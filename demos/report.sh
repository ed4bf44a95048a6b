#!/bin/sh
# demos/report.sh [DIR]: turn the JSON Lines of every benchmark in DIR
# (default build/bench) into per-suite tables on stdout and, with gnuplot,
# error-against-run-time scatter plots DIR/<suite>[_<variant>].png (log-log,
# one point per backend x case, colour and marker = backend, Minko
# drawn larger). `make bench` runs it last.
#
# Only POSIX sh and awk are needed for the tables (the JSON Lines of
# ../shared/BENCH_FORMAT.md are flat objects of strings and numbers); plots
# are skipped with a note when gnuplot is missing. Time axis: ns_per_query,
# else ms_per_frame, else collision_ms_per_frame. Error axis: rel_err_p99,
# else drift, else max_penetration. A suite with neither pair gets a table only.
set -eu
dir=${1:-build/bench}
files=$(ls "$dir"/*.jsonl 2>/dev/null || true)
if [ -z "$files" ]; then
    echo "report: no JSON Lines in $dir" >&2
    exit 0
fi
plotdir="$dir/plotdata"
rm -rf "$plotdir"
mkdir -p "$plotdir"

# shellcheck disable=SC2086
awk -v plotdir="$plotdir" '
# Parse one flat JSON object into kv[] (keys in order in keys[]).
function parse(line,    i, c, k, v, n, inq, tok, expect_key) {
    delete kv; nkeys = 0; n = length(line); tok = ""; inq = 0; expect_key = 1; k = ""
    for (i = 1; i <= n; ++i) {
        c = substr(line, i, 1)
        if (inq) {
            if (c == "\\") { tok = tok substr(line, i + 1, 1); ++i; continue }
            if (c == "\"") { inq = 0; continue }
            tok = tok c; continue
        }
        if (c == "\"") { inq = 1; continue }
        if (c == "{" || c == " ") continue
        if (c == ":") { k = tok; tok = ""; continue }
        if (c == "," || c == "}") {
            if (k != "") { kv[k] = tok; keys[++nkeys] = k }
            k = ""; tok = ""; continue
        }
        tok = tok c
    }
}
function num(x) { return x + 0 }
function fmtv(key, x) {
    if (x == "") return "-"
    if (key == "n" || key == "wrong_bool" || key == "failures" || key ~ /pairs$/ || key == "tunnelled") return sprintf("%d", x)
    if (key ~ /^ns_/) return sprintf("%.0f", x)
    return sprintf("%.2g", x)
}
BEGIN {
    split("ns_per_query ms_per_frame collision_ms_per_frame space_ms_per_frame rel_err_p50 rel_err_p99 rel_err_max normal_err_deg_p99 normal_err_deg_max wrong_bool failures missing_pairs extra_pairs tunnelled max_penetration ke_end drift", order, " ")
    norder = 17
}
/^[ \t]*\{/ {
    parse($0)
    s = kv["suite"]; if (s == "") next
    if (!(s in seen_suite)) { seen_suite[s] = 1; suites[++nsuites] = s }
    r = ++nrows[s]
    row_case[s, r] = kv["case"]; row_variant[s, r] = kv["variant"]; row_backend[s, r] = kv["backend"]; row_n[s, r] = kv["n"]
    for (j = 1; j <= norder; ++j) if (order[j] in kv) { row_val[s, r, order[j]] = kv[order[j]]; used[s, order[j]] = 1 }
    verdict[s, r] = ""
    for (j = 1; j <= nkeys; ++j) if (keys[j] ~ /^verdict/) verdict[s, r] = verdict[s, r] (verdict[s, r] == "" ? "" : " | ") kv[keys[j]]
    # error-vs-time points
    x = ""; y = ""
    if ("ns_per_query" in kv) { x = kv["ns_per_query"]; xname[s] = "ns per query" }
    else if ("ms_per_frame" in kv) { x = kv["ms_per_frame"]; xname[s] = "ms per frame" }
    else if ("collision_ms_per_frame" in kv) { x = kv["collision_ms_per_frame"]; xname[s] = "collision ms per frame" }
    if ("rel_err_p99" in kv) { y = kv["rel_err_p99"]; yname[s] = "relative error p99 (0 drawn at 1e-17)" }
    else if ("drift" in kv) { y = kv["drift"]; yname[s] = "drift" }
    else if ("max_penetration" in kv) { y = kv["max_penetration"]; yname[s] = "max penetration" }
    if (x != "" && y != "" && num(x) > 0) {
        np = ++npts[s]
        px[s, np] = x; py[s, np] = num(y) > 0 ? y : 1e-17
        pcase[s, np] = kv["case"]; pvar[s, np] = kv["variant"]; pback[s, np] = kv["backend"]
        if (!((s, kv["variant"], kv["case"]) in vc)) { vc[s, kv["variant"], kv["case"]] = 1; vcases[s, kv["variant"]]++ }
    }
}
END {
    for (i = 1; i <= nsuites; ++i) {
        s = suites[i]
        printf "\n== suite %s (%d rows)\n", s, nrows[s]
        hdr = sprintf("  %-18s %-22s %-28s %6s", "case", "variant", "backend", "n")
        for (j = 1; j <= norder; ++j) if ((s, order[j]) in used) hdr = hdr sprintf(" %9s", substr(order[j], 1, 9))
        print hdr
        for (r = 1; r <= nrows[s]; ++r) {
            line = sprintf("  %-18s %-22s %-28s %6s", substr(row_case[s, r], 1, 18), substr(row_variant[s, r], 1, 22), substr(row_backend[s, r], 1, 28), row_n[s, r])
            for (j = 1; j <= norder; ++j) if ((s, order[j]) in used) line = line sprintf(" %9s", fmtv(order[j], row_val[s, r, order[j]]))
            print line
            if (verdict[s, r] != "") print "      -> " verdict[s, r]
        }
        # Plot data: one file per variant that spans several cases (e.g.
        # separated / penetrating); variants met by a single case (named
        # regression cases) share one "other" plot. One block per backend.
        for (p = 1; p <= npts[s]; ++p) {
            g = vcases[s, pvar[s, p]] >= 2 ? pvar[s, p] : "other"
            tag = s "_" g
            gsub(/[^A-Za-z0-9_.=-]/, "_", tag)
            f = plotdir "/" tag ".dat"
            if (!(f in started)) { started[f] = 1; files[++nfiles] = f; ftitle[f] = "suite " s ", " g; fx[f] = xname[s]; fy[f] = yname[s] }
            if (!((f, pback[s, p]) in fb)) { fb[f, pback[s, p]] = ++nfb[f]; fbname[f, nfb[f]] = pback[s, p] }
            lab = g == "other" ? pvar[s, p] : pcase[s, p]
            blk[f, fb[f, pback[s, p]]] = blk[f, fb[f, pback[s, p]]] sprintf("%s %s %s\n", px[s, p], py[s, p], lab)
        }
    }
    for (k = 1; k <= nfiles; ++k) {
        f = files[k]
        # Minko blocks first, so the plot can draw them larger.
        nm = 0
        for (pass = 0; pass < 2; ++pass)
            for (b = 1; b <= nfb[f]; ++b)
                if (index(fbname[f, b], "minko") == 1 ? pass == 0 : pass == 1) {
                    printf "\"%s\" y case\n%s\n\n", fbname[f, b], blk[f, b] > f
                    if (pass == 0) ++nm
                }
        close(f)
        printf "%s\t%s\t%s\t%s\t%d\n", f, ftitle[f], fx[f], fy[f], nm > (plotdir "/index.tsv")
    }
}
' $files

if [ ! -f "$plotdir/index.tsv" ]; then
    exit 0
fi
if ! command -v gnuplot >/dev/null 2>&1; then
    echo "report: gnuplot not found; tables only (plot data in $plotdir)"
    exit 0
fi
here=$(dirname "$0")
while IFS="$(printf '\t')" read -r dat title xl yl nminko; do
    png="$dir/$(basename "$dat" .dat).png"
    blocks=$(grep -c '^"' "$dat")
    gnuplot -e "datafile='$dat'; outfile='$png'; plottitle='$title'; xlab='$xl'; ylab='$yl'; nblocks=$blocks; nminko=$nminko" \
        "$here/report.gp" && echo "report: $png"
done < "$plotdir/index.tsv"
