#!/usr/bin/env bash
# Build PRISM 4.10.1 from its public source for the side-by-side benchmark
# (benchmarks/prism_side_by_side.py). Optional: nothing in the tests needs PRISM.
#
#   bash benchmarks/prism_build.sh [SOURCE_DIR]     # default: .bench/prism
#
# SOURCE_DIR is a checkout of https://github.com/prismmodelchecker/prism at tag v4.10.1;
# when it does not exist, the script clones it. A source snapshot may lack the fastutil jar
# (a large file): Debian's libfastutil-java provides it (installed with apt-get as root).
# The build takes about 4 minutes of CPU (C++ and Java, `make`); the executable is
# SOURCE_DIR/prism/bin/prism.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
src="${1:-$here/.bench/prism}"
if [ ! -d "$src/prism" ]; then
    mkdir -p "$(dirname "$src")"
    git clone --depth 1 --branch v4.10.1 https://github.com/prismmodelchecker/prism "$src"
fi
jar="$(ls "$src"/prism/lib/fastutil-*.jar 2>/dev/null | head -1 || true)"
if [ -z "$jar" ] || [ ! -s "$jar" ] || ! unzip -tq "$jar" >/dev/null 2>&1; then
    if [ ! -f /usr/share/java/fastutil.jar ]; then
        if [ "$(id -u)" = 0 ]; then
            apt-get update -qq && apt-get install -y -qq libfastutil-java
        else
            echo "prism_build: the fastutil jar is missing; install Debian's libfastutil-java" >&2
            exit 1
        fi
    fi
    cp /usr/share/java/fastutil.jar "$src/prism/lib/fastutil-8.5.15.jar"
fi
command -v javac >/dev/null || { echo "prism_build: needs a JDK (javac) and g++" >&2; exit 1; }
(cd "$src/prism" && make -j"$(nproc)")
echo "built $src/prism/bin/prism"
