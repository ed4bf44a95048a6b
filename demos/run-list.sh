#!/bin/sh
# demos/run-list.sh WORD...: run the DEMO_RUNS / BENCH_RUNS lists of the
# Makefile. Fragments append "program arg arg" entries with +=, which make
# joins with spaces, so the entries are cut apart again here: a word that
# names an executable file starts a new command. Commands run one after
# another (benchmarks never share the CPU) and the first failure stops the list.
set -eu
run() {
    [ -n "$1" ] || return 0
    echo ">> $1"
    # shellcheck disable=SC2086
    $1
}
cmd=""
for w in "$@"; do
    if [ -n "$cmd" ] && [ -f "$w" ] && [ -x "$w" ]; then
        run "$cmd"
        cmd="$w"
    else
        cmd="${cmd:+$cmd }$w"
    fi
done
run "$cmd"
