#!/bin/sh
# Fuzzes the .lbm decoder for a set time: a thin wrapper kept for old habits.
# usage: scripts/fuzz-valence.sh [SECONDS]   (default 60)
exec "$(dirname "$0")/fuzz.sh" valence "${1:-60}"
