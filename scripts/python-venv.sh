#!/usr/bin/env bash
# Makes the project-local Python venv DIR with PACKAGES, once. It is built in place (a venv's
# scripts name its folder, so one built elsewhere and moved is broken) and marked ready only
# at the end: a failed or interrupted pip install never looks like a ready venv, and the next
# run makes it again.
# Usage: scripts/python-venv.sh DIR CHECK PACKAGE...
#   CHECK: a Python statement that succeeds only in a ready venv (e.g. "import cv2").
set -euo pipefail
cd "$(dirname "$0")/.."
dir=$1 check=$2
shift 2
ready="$dir/.specchio-ready"
if [ -f "$ready" ] && [ -x "$dir/bin/python" ] && "$dir/bin/python" -c "$check" 2>/dev/null; then
    exit 0
fi
if ! python3 -m venv --help >/dev/null 2>&1 || ! python3 -c "import ensurepip" 2>/dev/null; then
    echo "setup: installing python3-venv (for the project's venvs)" >&2
    if [ "$(id -u)" -eq 0 ]; then apt-get update -qq && apt-get install -y -qq python3-venv >/dev/null
    else sudo apt-get update -qq && sudo apt-get install -y -qq python3-venv >/dev/null
    fi
fi
echo "setup: making $dir (${*})" >&2
rm -rf "$dir"
python3 -m venv "$dir"
"$dir/bin/pip" install --quiet --disable-pip-version-check "$@"
"$dir/bin/python" -c "$check"
touch "$ready"
