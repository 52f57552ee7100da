#!/bin/sh
# The compiler launcher (cmake/EpipoleCcache.cmake): runs the compiler command through ccache and,
# when the command makes a precompiled header (-o X.gch or X.pch), writes X.gch.sum (X.pch.sum)
# beside it: the header's checksum. With pch_external_checksum, ccache hashes that small file
# instead of the header itself, over 100 MB, on every compile that uses it; without it a cache hit
# of a test file took 0.65 s, with it 0.04 s.
#
#   ccache-launcher.sh CCACHE COMPILER ARGS...
out=
next_is_output=0
for arg in "$@"; do
  if [ "$next_is_output" = 1 ]; then
    out=$arg
    next_is_output=0
  fi
  if [ "$arg" = -o ]; then next_is_output=1; fi
done
case $out in
  *.gch | *.pch)
    rm -f "$out.sum"  # never a stale checksum, even if the compile fails
    "$@" || exit
    sum=$(b2sum "$out") || exit
    printf '%s\n' "${sum%% *}" >"$out.sum"
    ;;
  *) exec "$@" ;;
esac
