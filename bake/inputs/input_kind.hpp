// What kind of clothbake input a file holds, from its bytes: so that a fabric given where a scene
// is needed (or a scene, an asset or a WIF draft where a fabric is) gets "this is a scene, not a
// fabric" rather than a TOML syntax error or an unknown key.
#pragma once

#include <string>
#include <string_view>

namespace clothbake::inputs {

enum class InputKind { Fabric, Scene, Wif, Asset, Unknown };

// "fabric description", "scene", "WIF draft", "clothbake asset", "file of another kind".
const char* input_kind_name(InputKind kind);

// An asset by its 8-byte magic; a WIF draft by a "[WIF]" section header (any case); a scene by a
// top-level [camera], [[light]], [[object]] or [render] header; a fabric by [maps], [weave],
// [[yarn]], [tile], [sheen] or [bake]; Unknown otherwise (or when both a scene's and a fabric's
// headers appear). Only headers at the start of a line (after blanks) count; nothing is parsed.
// Safe on any bytes; no allocation beyond the result.
InputKind sniff_input_kind(std::string_view bytes);

// Throws Error(Input) "PATH is a KIND, not a EXPECTED: NEEDS" when `kind` (sniff_input_kind of
// the file) is known and differs from `expected` (Unknown passes: the loader's own error names the
// problem).
void require_input_kind(InputKind kind, const std::string& path, InputKind expected,
                        const std::string& needs);

}  // namespace clothbake::inputs
