// Reading law parameters and material-point states from small TOML files (docs/models.md "Model
// envelopes and `rendulic envelope`"). Kept apart from the laws (no I/O inside physics classes).
//   parameters file: keys are the law's parameter names, numeric values; missing keys keep
//     their defaults; an unknown key or a value out of bounds is an InputError naming the key
//     and the file.
//   state file: `stress` (3x3 array, Pa, compression positive, required), `fabric` (3x3,
//     optional, default zero), `volume_fraction` (optional, default 0: no law uses it yet).
#pragma once

#include <string>

#include "rendulic/models/law.hpp"

namespace rendulic::models {

// Throws rendulic::InputError on any problem.
void load_parameters_toml(const std::string& path, Law* law);
MaterialState load_state_toml(const std::string& path, const Law& law);
// The same from TOML text (from_text; else `path` is read), `path` naming it in the messages:
// the Python module's dictionaries, checked exactly as a file is.
void parse_parameters_toml(const std::string& text, const std::string& path, Law* law,
                           bool from_text = true);
MaterialState parse_state_toml(const std::string& text, const std::string& path, const Law& law,
                               bool from_text = true);

}  // namespace rendulic::models
