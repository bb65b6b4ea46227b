#!/usr/bin/env bash
# Used by the Dockerfile's build stage: copies into DEST what the runtime
# stage needs, and nothing else: the given files and folders (symlinks
# followed, Python caches and test suites left out) and every shared library
# that an ELF file among them loads (their ldd closure), into
# DEST/usr/lib/x86_64-linux-gnu/ under the name the loader asks for. A
# library listed in BASE_LIBS (the base image's library folder, written
# before anything was installed) is not copied: the runtime base has it.
#
# usage: docker_runtime_files.sh DEST BASE_LIBS PATH...
# Installing the runtime packages with apt instead would bring their whole
# dependency trees: libopencv-imgcodecs406 needs GDAL and its data, and
# python3-matplotlib needs scipy and a C++ compiler through python3-fonttools
# (1.17 GB in all on Debian 12).
set -euo pipefail
dest="$1"
base_libs="$2"
shift 2
libdir=/usr/lib/x86_64-linux-gnu

elf_files=()
for path in "$@"; do
  mkdir -p "$dest$(dirname "$path")"
  if [ -d "$path" ]; then
    tar -C / -ch --exclude=__pycache__ --exclude=tests --exclude=test --exclude=idlelib --exclude=tkinter \
      --exclude=ensurepip --exclude=lib2to3 --exclude='config-3*' --exclude=turtledemo --exclude='*.pyc' "${path#/}" | tar -C "$dest" -x
  else
    cp -L "$path" "$dest$path"
  fi
  while IFS= read -r file; do
    case "$(head -c 4 "$file" | od -An -c | tr -d ' ')" in 177ELF) elf_files+=("$file") ;; esac
  done < <(find "$dest$path" -type f \( -name '*.so*' -o -perm -u+x \))
done

mkdir -p "$dest$libdir"
declare -A copied=()
for file in "${elf_files[@]}"; do
  # ldd lines: "libfoo.so.1 => /lib/x86_64-linux-gnu/libfoo.so.1 (0x...)"
  while read -r name arrow resolved _; do
    [ "$arrow" = "=>" ] && [ -f "$resolved" ] || continue
    [ -z "${copied[$name]:-}" ] || continue
    copied[$name]=1
    grep -qx "$name" "$base_libs" && continue
    cp -L "$resolved" "$dest$libdir/$name"
  done < <(ldd "$file" 2>/dev/null || true)
done
missing="$(for file in "${elf_files[@]}"; do ldd "$file" 2>/dev/null | grep "not found" || true; done | sort -u)"
if [ -n "$missing" ]; then
  echo "docker_runtime_files: libraries not found: $missing" >&2
  exit 1
fi
echo "docker_runtime_files: ${#elf_files[@]} programs and modules, ${#copied[@]} libraries;" \
  "$(du -sh "$dest" | cut -f1) in $dest"
