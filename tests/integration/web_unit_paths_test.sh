#!/usr/bin/env bash
# web_unit_paths_test.sh — can findmug-web write where its config says it writes, under
# its unit's hardening? Reads the unit (ProtectSystem, ProtectHome, PrivateTmp,
# DynamicUser, ReadWritePaths, ReadOnlyPaths, InaccessiblePaths and the
# State/Cache/Logs/RuntimeDirectory it gets) and the web config, and fails naming each
# written path the service could not write:
#   web.jobs_dir (each Retrain job's folder), the folder of web.install_path (Install
#   writes INSTALL_PATH.new there and renames it), and every further PATH given (data
#   folders the page labels into: label8/, drafts/; where the unit's comment says to put
#   jobs and models).
# No systemd runs as PID 1 here, so the unit's rules are applied to the paths by this
# script (systemd.exec(5)); findmug-web's data folders are only known from the command
# line, hence the PATH arguments.
#
#   web_unit_paths_test.sh UNIT_FILE WEB_CONFIG [PATH...]
# Exit 0: every path writable; 1: one is not (each printed, on stdout); 2: bad usage.
set -euo pipefail
[[ $# -ge 2 && -f "$1" && -f "$2" ]] || { echo "usage: $0 UNIT_FILE WEB_CONFIG [PATH...]" >&2; exit 2; }
unit=$1 config=$2
shift 2

# The unit's [Service] settings; a setting given more than once accumulates (lists) or
# the last one wins (booleans), as systemd reads them.
setting_all() { sed -n "/^\[Service\]/,/^\[/ s/^$1=//p" "$unit"; }
setting_last() { setting_all "$1" | tail -1; }
words() { setting_all "$1" | tr ' ' '\n' | sed '/^$/d; s/^[-+]//'; }

dynamic=$(setting_last DynamicUser)
protect_system=$(setting_last ProtectSystem)
protect_home=$(setting_last ProtectHome)
private_tmp=$(setting_last PrivateTmp)
# DynamicUser=yes implies ProtectSystem=strict, ProtectHome=read-only, PrivateTmp=yes.
if [[ $dynamic == yes ]]; then
  protect_system=strict
  [[ -z $protect_home || $protect_home == no ]] && protect_home=read-only
  private_tmp=yes
fi

# Folders the service owns and may write (made by systemd for the service's user).
owned=()
for kind in State:/var/lib Cache:/var/cache Logs:/var/log Runtime:/run; do
  for d in $(words "${kind%%:*}Directory"); do owned+=("${kind#*:}/$d"); done
done
[[ $private_tmp == yes ]] && owned+=(/tmp /var/tmp)
mapfile -t read_write < <(words ReadWritePaths)
mapfile -t read_only < <(words ReadOnlyPaths)
mapfile -t inaccessible < <(words InaccessiblePaths)

under() {  # PATH DIR: PATH is DIR or inside it
  [[ $1 == "$2" || $1 == "$2"/* ]]
}

# Why PATH is not writable for the service ("" when it is).
blocked() {
  local p=$1 d
  for d in "${inaccessible[@]}"; do under "$p" "$d" && { echo "InaccessiblePaths=$d"; return; }; done
  for d in "${read_only[@]}"; do under "$p" "$d" && { echo "ReadOnlyPaths=$d"; return; }; done
  for d in "${owned[@]}"; do under "$p" "$d" && return; done
  for d in "${read_write[@]}"; do
    if under "$p" "$d"; then
      # A dynamic user owns nothing outside its own directories: a ReadWritePaths folder
      # is writable only if its permissions let any user write.
      [[ $dynamic == yes ]] && { echo "ReadWritePaths=$d, but DynamicUser=yes owns nothing there (use StateDirectory=)"; return; }
      return
    fi
  done
  case "$protect_system" in
    strict) echo "ProtectSystem=strict (only StateDirectory=, ReadWritePaths=, ... are writable)"; return ;;
    full) for d in /usr /boot /efi /etc; do under "$p" "$d" && { echo "ProtectSystem=full"; return; }; done ;;
    yes|true) for d in /usr /boot /efi; do under "$p" "$d" && { echo "ProtectSystem=yes"; return; }; done ;;
  esac
  if [[ -n $protect_home && $protect_home != no && $protect_home != false ]]; then
    for d in /home /root /run/user; do under "$p" "$d" && { echo "ProtectHome=$protect_home"; return; }; done
  fi
  if [[ $dynamic == yes ]]; then echo "DynamicUser=yes owns nothing at $p"; return; fi
}

# web: section values (two-space indented keys, as the shipped file writes them).
web_value() {
  sed -n '/^web:/,/^[^ #]/ s/^  '"$1"': *//p' "$config" | sed 's/ *#.*//; s/^"\(.*\)"$/\1/' | tail -1
}
written=()
jobs_dir=$(web_value jobs_dir)
install_path=$(web_value install_path)
[[ -n $jobs_dir ]] && written+=("web.jobs_dir:$jobs_dir")
[[ -n $install_path ]] && written+=("web.install_path's folder:$(dirname "$install_path")")
for p in "$@"; do written+=("folder:$p"); done
[[ ${#written[@]} -gt 0 ]] || { echo "web_unit_paths_test: $config writes nowhere and no PATH given: nothing to check" >&2; exit 2; }

bad=0
for w in "${written[@]}"; do
  what=${w%%:*} p=${w#*:}
  [[ $p == /* ]] || { echo "web_unit_paths_test: $what '$p' is not an absolute path" >&2; bad=1; continue; }
  why=$(blocked "$p")
  if [[ -n $why ]]; then
    echo "web_unit_paths_test: $what $p is not writable under $(basename "$unit"): $why"
    bad=1
  else
    echo "web_unit_paths_test: $what $p writable"
  fi
done
exit $bad
