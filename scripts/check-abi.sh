#!/bin/sh
# The precision guard must hold (needs build/ and build/single/ built):
#  1. an application compiled with -DMK_SINGLE against the double headers does not compile;
#  2. an object compiled for double does not link with the single library, and the reverse;
#  3. matching precision compiles and links.
set -eu
CC="${1:-cc}"
t=build/abi-check
mkdir -p $t
cat > $t/app.c <<'C'
#include "minko/base.h"
int main(void) { return mk_version() > 0 ? 0 : 1; }
C
fail=0
if $CC -std=c99 -DMK_SINGLE -Ibuild/include -Iinclude -c $t/app.c -o $t/bad.o 2>/dev/null; then
    echo "check-abi: -DMK_SINGLE compiled against the double config header" >&2; fail=1
fi
$CC -std=c99 -Ibuild/include -Iinclude -c $t/app.c -o $t/d.o
$CC -std=c99 -Ibuild/single/include -Iinclude -c $t/app.c -o $t/s.o
$CC $t/d.o build/libminko.a -lm -o $t/ok_d || { echo "check-abi: double app did not link with double lib" >&2; fail=1; }
$CC $t/s.o build/single/libminko.a -lm -o $t/ok_s || { echo "check-abi: single app did not link with single lib" >&2; fail=1; }
if $CC $t/d.o build/single/libminko.a -lm -o $t/bad_ds 2>/dev/null; then
    echo "check-abi: double app linked with the single library" >&2; fail=1
fi
if $CC $t/s.o build/libminko.a -lm -o $t/bad_sd 2>/dev/null; then
    echo "check-abi: single app linked with the double library" >&2; fail=1
fi
[ $fail -eq 0 ] && echo "check-abi: precision mismatches fail to compile or link; matching builds link."
exit $fail
