#!/bin/sh
# Rewrites old flat core paths (findmug/X.hpp, src/X.cpp) to their rooms in every tracked file.
# Run after merging a branch that predates the move into rooms (scripts/dev/rooms.py).
exec python3 "$(dirname "$0")/rooms.py" includes
