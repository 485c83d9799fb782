// The 3DGS half of stream_deform() (stream_deform.h): chunks of vertex rows become GaussianClouds, are
// deformed by gaussian::deform (or its GPU deformer) and written back into the same columns.
#pragma once

#include "runtime/assets/formats/surface/ply.h"
#include "systems/ffd/stream_deform.h"

namespace sffd::ffd::detail {

// `reader` is the opened input (its header checked by stream_deform()); request.lattices holds one lattice.
Result<StreamDeformResult> stream_gaussians(const StreamDeformRequest& request, ply::Reader& reader,
                                            const StreamProgress& progress);

}  // namespace sffd::ffd::detail
