#!/usr/bin/env bash
# Builds the manual (docs/, mkdocs.yml) into build/site with Debian's mkdocs, after checking that
# every relative link of README.md and docs/ leads to a file and heading that exist.
# scripts/docs.sh [SITE_DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
site=${1:-$root/build/site}
command -v mkdocs >/dev/null || {
  echo "docs.sh: mkdocs not found; scripts/install-deps.sh installs it (Debian's mkdocs)" >&2
  exit 2
}
python3 "$root/scripts/check-docs-links.py" "$root"
cd "$root"
mkdocs build --quiet --clean --site-dir "$site"
echo "docs.sh: the manual is in $site/index.html"
