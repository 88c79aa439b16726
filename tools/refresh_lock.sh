#!/usr/bin/env bash
# Refresh or check requirements.lock.txt, the exact, tested versions of every dependency.
#
#   tools/refresh_lock.sh          # resolve the newest versions pyproject.toml allows in a new
#                                  # virtual environment, run the test suite there, and write the
#                                  # lock only if every test passes
#   tools/refresh_lock.sh --check  # install the current lock in a new virtual environment from a
#                                  # clean clone and run the README's two commands there
#   tools/refresh_lock.sh --add    # as the refresh, but through the current lock: every locked
#                                  # version kept, only what the lock lacks (a new dependency) is
#                                  # resolved; the lock is rewritten only if every test passes
#
# See docs/dev/environment.md. Needs the package registry (pip) and about 15 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
mode=${1:-refresh}
case $mode in
    refresh|--check|--add) ;;
    *) echo "usage: tools/refresh_lock.sh [--check|--add]" >&2; exit 2 ;;
esac
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
git clone --quiet "$repo" "$work/clone"
cp -p pyproject.toml requirements.lock.txt "$work/clone/" # uncommitted edits to these count
python3 -m venv "$work/venv"
py="$work/venv/bin/python"
"$py" -m pip install --quiet --disable-pip-version-check --upgrade pip
cd "$work/clone"
if [ "$mode" = "--check" ] || [ "$mode" = "--add" ]; then
    "$py" -m pip install --quiet --disable-pip-version-check -c requirements.lock.txt -e ".[test]"
else
    "$py" -m pip install --quiet --disable-pip-version-check -e ".[test]"
fi
PATH="$work/venv/bin:$PATH" snakemake --cores 2
PATH="$work/venv/bin:$PATH" "$py" -m pytest -n 2
if [ "$mode" = "--check" ]; then
    echo "lock check passed: $("$py" -m pip freeze --exclude-editable | wc -l) pinned distributions"
    exit 0
fi
{
    echo "# Exact, tested versions of every dependency of ttbpipe (pip constraints file)."
    echo "# Installed by the README's first command and by .ci/run:"
    echo "#   pip install -c requirements.lock.txt -e \".[test]\""
    echo "# Made by tools/refresh_lock.sh$([ "$mode" = "--add" ] && echo " --add") on $(date -u +%Y-%m-%d) with $("$py" --version) on"
    echo "# $(uname -s) $(uname -m); the test suite passed with exactly these versions."
    "$py" -m pip freeze --exclude-editable --disable-pip-version-check
} > "$repo/requirements.lock.txt.new"
mv "$repo/requirements.lock.txt.new" "$repo/requirements.lock.txt"
echo "wrote requirements.lock.txt"
