#!/bin/sh
# Fails if libminko.so exports any symbol without the mk_ prefix, or if a
# function the public headers declare with MK_API is not exported.
set -eu
so="$1"
# ASan adds its own __odr_asan.<name> guards next to our globals; those are not ours.
bad=$(nm -D --defined-only "$so" | awk '{print $3}' | grep -v '^mk_' | grep -v '^__odr_asan\.mk_' || true)
if [ -n "$bad" ]; then
    echo "check-exports: $so exports symbols without the mk_ prefix:" >&2
    echo "$bad" >&2
    exit 1
fi
exported=$(nm -D --defined-only "$so" | awk '{print $3}' | sort)
want=$(grep -ho 'MK_API[^;{(]*[ *]\(mk_[a-z0-9_]*\) *(' include/minko/*.h | sed 's/.*[ *]\(mk_[a-z0-9_]*\) *(/\1/' | sort -u)
missing=""
for f in $want; do
    echo "$exported" | grep -qx "$f" || missing="$missing $f"
done
if [ -n "$missing" ]; then
    echo "check-exports: declared MK_API but not exported by $so:$missing" >&2
    exit 1
fi
echo "check-exports: $(echo "$exported" | wc -l) symbols, all mk_-prefixed; every MK_API function is exported."
