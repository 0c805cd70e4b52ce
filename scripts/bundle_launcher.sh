#!/bin/sh
# The launcher of a bundle made by scripts/bundle.sh (copied there as `run`): `run NAME ARGS...` runs bin/NAME with the
# bundle's libraries first on LD_LIBRARY_PATH (what the caller had there stays after them, e.g. a GPU driver's folder).
# lib/compat (libstdc++, libgcc_s) joins them only where the system's libstdc++ is older than the build's
# (MIPNERF_BUNDLE_COMPAT=1 or 0 decides instead). OpenCL drivers come from OCL_ICD_VENDORS, else /etc/OpenCL/vendors.
here=$(cd "$(dirname "$0")" && pwd)
glibc_needed="@GLIBC_NEEDED@"
glibcxx_needed="@GLIBCXX_NEEDED@"

name="${1:-}"
if [ -z "$name" ] || [ ! -x "$here/bin/$name" ]; then
  echo "bundle: run NAME [ARGS...], NAME one of: $(ls "$here/bin" | tr '\n' ' ')" >&2
  exit 127
fi
shift

# older A B: whether version A sorts before version B.
older() { [ "$1" != "$2" ] && [ "$(printf '%s\n%s\n' "$1" "$2" | sort -V | head -n 1)" = "$1" ]; }

glibc_here=$(getconf GNU_LIBC_VERSION 2>/dev/null | awk '{print $2}')
if [ -n "$glibc_here" ] && older "$glibc_here" "$glibc_needed"; then
  echo "bundle: built against glibc $glibc_needed, this system has $glibc_here: build the bundle on an older system" >&2
  exit 1
fi

# system_libstdcxx_is_new_enough: the system's libstdc++.so.6 defines the newest symbol version the bundle uses.
system_libstdcxx_is_new_enough() {
  for candidate in $(ldconfig -p 2>/dev/null | awk '/libstdc\+\+\.so\.6 .*x86-64/ {print $NF}') \
      /usr/lib/x86_64-linux-gnu/libstdc++.so.6 /lib/x86_64-linux-gnu/libstdc++.so.6 /usr/lib64/libstdc++.so.6; do
    if [ -r "$candidate" ]; then
      grep -q "GLIBCXX_$glibcxx_needed" "$candidate"
      return
    fi
  done
  return 1
}

libraries="$here/lib"
case "${MIPNERF_BUNDLE_COMPAT:-auto}" in
  1) libraries="$libraries:$here/lib/compat" ;;
  0) ;;
  *) system_libstdcxx_is_new_enough || libraries="$libraries:$here/lib/compat" ;;
esac
LD_LIBRARY_PATH="$libraries${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export LD_LIBRARY_PATH
exec "$here/bin/$name" "$@"
