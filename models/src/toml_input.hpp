// The models' small TOML input files (docs/models.md "Model envelopes and `rendulic envelope`",
// docs/umat.md): law parameters, a material-point state and a UMAT's PROPS, read through
// core's read_input_text (a FIFO, a folder or a device is refused in one line, not read or
// waited on) and parsed, a syntax error becoming one InputError "PATH:LINE: reason".
// Private to rendulic::models.
#pragma once

#include <toml++/toml.h>

#include <string>

namespace rendulic::models {

// The file at `path` (`what` names its kind in messages: "parameter file"), or, when `text` is
// given, that text with `path` naming it.
toml::table parse_toml_input(const std::string& path, const std::string& what,
                             const std::string* text = nullptr);

}  // namespace rendulic::models
