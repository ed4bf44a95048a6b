#!/bin/sh
# ode_ratios.sh: issue 7's statistics from an ode_scenes --per-frame file.
#
#   demos/ode_ratios.sh FILE
#
# FILE holds one JSON line per frame (or step) and backend, as written by
#   build/demos/ode_scenes --scene stress_space --poses P --per-frame FILE   (replay)
#   build/demos/ode_scenes --scene stress --per-frame FILE                    (running simulation)
#   build/demos/ode_scenes --scene stress --load-state S25 --per-frame FILE   (its steps 25..99 only)
# where S25 was saved once by
#   build/demos/ode_scenes --scene stress --backend ode.sap --steps 25 --save-state S25
# (the restart continues the running simulation bit for bit; see ode_scenes.c).
# For each case in the file and each Minko backend in it (a name starting
# with "minko"), its space collide time against the faster of ODE's two
# spaces (ode.hash, ode.sap), four ways, since the mean and the median of a
# heap that starts dense disagree:
#   ratio of medians   median(minko) / the lower of the two ODE medians
#   median of ratios   per frame minko / the faster ODE space at that frame, then the median
#   mean of ratios     the same, averaged
#   ratio of means     mean(minko) / the lower of the two ODE means
# Frames where a space has no time are left out of that space's figures.
# Only POSIX sh and awk.
set -eu
if [ $# -ne 1 ] || [ ! -r "$1" ]; then
    echo "usage: $0 PER_FRAME_FILE" >&2
    exit 2
fi
awk '
function field(line, name,    m) {
    if (!match(line, "\"" name "\":\"?[^,\"}]*")) return ""
    m = substr(line, RSTART, RLENGTH)
    sub("^\"" name "\":\"?", "", m)
    return m
}
function median(v, n,    i, j, t) { # insertion sort of v[1..n] (n is at most a few hundred)
    for (i = 2; i <= n; i++) {
        t = v[i]
        for (j = i - 1; j >= 1 && v[j] > t; j--) v[j + 1] = v[j]
        v[j + 1] = t
    }
    return n % 2 ? v[(n + 1) / 2] : 0.5 * (v[n / 2] + v[n / 2 + 1])
}
function stats(c, b,    f, n, s, v) { # mean and median of case c, backend b over its frames
    n = 0; s = 0
    for (f = 0; f <= maxf[c]; f++) if ((c, b, f) in t) { v[++n] = t[c, b, f]; s += t[c, b, f] }
    cnt = n
    mean_ = n ? s / n : 0
    med_ = n ? median(v, n) : 0
}
{
    c = field($0, "case"); b = field($0, "backend"); ms = field($0, "space_ms")
    f = field($0, "frame"); if (f == "") f = field($0, "step")
    if (c == "" || b == "" || ms == "" || f == "") next
    t[c, b, f] = ms + 0
    if (!((c, b) in seen)) { seen[c, b] = 1; names[c] = names[c] " " b }
    if (!(c in maxf) || f + 0 > maxf[c]) maxf[c] = f + 0
}
END {
    for (c in names) {
        if (!((c, "ode.hash") in seen) || !((c, "ode.sap") in seen)) continue
        stats(c, "ode.hash"); hmean = mean_; hmed = med_
        stats(c, "ode.sap"); smean = mean_; smed = med_
        printf "%s: ode.hash median %.4g mean %.4g ms, ode.sap median %.4g mean %.4g ms\n", c, hmed, hmean, smed, smean
        nb = split(names[c], bs, " ")
        for (k = 1; k <= nb; k++) {
            b = bs[k]
            if (b !~ /^minko/) continue
            stats(c, b)
            n = 0; s = 0
            for (f = 0; f <= maxf[c]; f++) {
                if (!((c, b, f) in t) || !((c, "ode.hash", f) in t) || !((c, "ode.sap", f) in t)) continue
                best = t[c, "ode.hash", f] < t[c, "ode.sap", f] ? t[c, "ode.hash", f] : t[c, "ode.sap", f]
                if (best <= 0) continue
                r[++n] = t[c, b, f] / best; s += r[n]
            }
            printf "  %-10s %d frames, median %.4g mean %.4g ms: ratio of medians %.3f, median of ratios %.3f, mean of ratios %.3f, ratio of means %.3f\n",
                b, cnt, med_, mean_, med_ / (hmed < smed ? hmed : smed), n ? median(r, n) : 0, n ? s / n : 0,
                mean_ / (hmean < smean ? hmean : smean)
        }
    }
}' "$1"
