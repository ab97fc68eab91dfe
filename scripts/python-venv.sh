#!/usr/bin/env bash
# Makes the project-local Python venv DIR with PACKAGES, once: built as DIR.new and moved into
# place only whole, so that a failed pip install never looks like a ready venv.
# Usage: scripts/python-venv.sh DIR CHECK PACKAGE...
#   CHECK: a Python statement that succeeds only in a ready venv (e.g. "import cv2").
set -euo pipefail
cd "$(dirname "$0")/.."
dir=$1 check=$2
shift 2
if [ -x "$dir/bin/python" ] && "$dir/bin/python" -c "$check" 2>/dev/null; then
    exit 0
fi
if ! python3 -m venv --help >/dev/null 2>&1 || ! python3 -c "import ensurepip" 2>/dev/null; then
    echo "setup: installing python3-venv (for the project's venvs)" >&2
    if [ "$(id -u)" -eq 0 ]; then apt-get update -qq && apt-get install -y -qq python3-venv >/dev/null
    else sudo apt-get update -qq && sudo apt-get install -y -qq python3-venv >/dev/null
    fi
fi
echo "setup: making $dir (${*})" >&2
rm -rf "$dir" "$dir.new"
python3 -m venv "$dir.new"
"$dir.new/bin/pip" install --quiet --disable-pip-version-check "$@"
# The venv's scripts name their folder: made as .new, it is rebuilt in place.
mv "$dir.new" "$dir"
python3 -m venv --upgrade "$dir" >/dev/null
# (pip's scripts still name the .new interpreter: run tools as `$dir/bin/python -m TOOL`.)
"$dir/bin/python" -c "$check"
