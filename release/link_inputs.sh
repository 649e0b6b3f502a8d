# Links to input files that never replace a file: sourced by the training scripts of release/ and research/.
# A link already there to the same file is kept; anything else under the name (a user's file, a folder, a link to
# another file) stops the script with an error, so that a work folder given by mistake loses nothing.
#
#   source release/link_inputs.sh
#   link_into FOLDER PATH...      makes FOLDER/NAME -> PATH for each PATH
#   link_as LINK PATH             makes LINK -> PATH

link_as() {
    local link=$1 source=$2 target
    if [[ ! -e "$source" ]]; then
        echo "error: cannot link to $source: no such file" >&2
        return 1
    fi
    target=$(realpath "$source")
    if [[ -L "$link" && "$link" -ef "$source" ]]; then
        return 0
    fi
    if [[ -e "$link" || -L "$link" ]]; then
        echo "error: $link is in the way (not a link to $target); move it away or choose another work folder" >&2
        return 1
    fi
    ln -s "$target" "$link"  # without -f: refuses, rather than replaces, whatever appeared meanwhile
}

link_into() {
    local folder=$1 path
    shift
    for path in "$@"; do
        link_as "$folder/$(basename "$path")" "$path" || return 1
    done
}
