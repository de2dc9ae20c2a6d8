// The one writer and reader of the envelope record (envelope_record.hpp) in the results file
// (docs/results.md, /states/<label>/envelopes/<name>). Kept apart from the record so that the
// engine, which fills records, never sees HDF5 (docs/architecture.md "Module layers").
#pragma once

#include <string>

#include "rendulic/core/envelope_record.hpp"
#include "rendulic/core/results.hpp"

namespace rendulic {

// std::logic_error if the record's sizes disagree (a bug of its maker, not bad input).
void write_envelope(ResultsWriter& out, const std::string& group, const EnvelopeRecord& envelope);

// What is stored at `group`, every part optional but the group itself: an envelope that could
// not be measured holds only attributes (its `error` says why), and files from elsewhere may
// lack what our writer adds. A missing amplitude reads as NaN, a missing method as "". Empty
// datasets read as absent. InputError (naming the file and group) if the group is missing,
// a dataset is malformed, or the non-empty per-probe datasets (and `directions`) disagree in
// length.
EnvelopeRecord read_envelope(const ResultsReader& in, const std::string& group);

}  // namespace rendulic
