#pragma once
// Internal to the TDMS reader (tdms.cpp): the NI scaling of a channel's raw values
// (tdms_scaling.cpp). Not for other code: the reader's interface is acquisition/session/tdms.h.
#include <string>

#include "acquisition/session/tdms.h"

namespace doorbench::tdms_detail {

// Applies the channel's NI_Scaling_* / NI_Scale[n]_* chain to its raw values (a DAQmx
// channel's scalers' raw values when it has them), replacing them by the scaled ones; a
// channel without scaling properties is left as it is. Throws naming `source`, the channel
// and the scale for a scale type that is not supported or a property that is missing.
void apply_scaling(TdmsChannel& channel, const std::string& source);

}  // namespace doorbench::tdms_detail
