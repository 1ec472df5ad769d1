// The light-field descriptor (Chen, Tian, Shen and Ouhyoung 2003): a model is seen in silhouette from
// the 20 vertices of a dodecahedron (10 views: opposite vertices see mirrored silhouettes), each view
// described by 35 Zernike moments (the region) and 10 Fourier coefficients of its outline (the
// contour), all magnitudes, so a view's turn or mirroring in the image plane does not matter. Ten such
// light fields, each with the dodecahedron turned another way, sample the rotations; two models'
// distance is the least over the 60 rotations of the dodecahedron onto itself and over the pairs of
// light fields, of the sum of the L1 distances of matched views. Silhouettes are drawn by the renderer.
#pragma once

#include "voxelize/TriangleMesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace vdbclay::render {
class ModelViews;
}

namespace vdbclay::query {

constexpr int kLightFields = 10;
constexpr int kViewsPerLightField = 10;
constexpr int kZernikeMoments = 35;
constexpr int kFourierCoefficients = 10;
constexpr int kViewFeatures = kZernikeMoments + kFourierCoefficients;
/// The vector's layout: kViewFeatures of the mean over all views (what FLANN's shortlist compares),
/// then each light field's views' features.
constexpr std::size_t kLightFieldLength = std::size_t(kViewFeatures) * (1 + kLightFields * kViewsPerLightField);
/// Silhouettes are drawn this many pixels square.
constexpr int kSilhouetteSize = 128;
/// Vertices drawn in silhouettes are clustered in cells this many pixels wide (SilhouetteMesh.h): below
/// what the features resolve (moments and outline coefficients of order 10, about a tenth of the view).
constexpr double kSilhouetteCellPixels = 1.0;

/// The view directions: light field f's view v at f * kViewsPerLightField + v.
const std::vector<std::array<double, 3>>& lightFieldDirections();

/// One view's features from its silhouette (size x size, rows top to bottom, non-zero inside), the
/// unit disk inscribed in the square.
std::array<float, kViewFeatures> silhouetteFeatures(const std::vector<uint8_t>& mask, int size);

/// The descriptor from the silhouettes of every direction of lightFieldDirections(), in its order.
std::vector<float> lightFieldFromSilhouettes(const std::vector<std::vector<uint8_t>>& masks, int size);

/// Draws the silhouettes of `mesh` (centred on its surface's centroid, the sphere through its farthest
/// vertex filling the view) and describes them. Throws std::invalid_argument for a mesh without area.
std::vector<float> lightFieldDescriptor(render::ModelViews& views, const TriangleSoup& mesh);

/// The light-field distance of a query `a` to a model `b`: L1, least over the 60 rotations and over the
/// pairs of `a`'s first `queryFields` light fields with all of `b`'s. One query field against ten already
/// tries 600 relative turns; the synthetic set ranks as well as with all 100 pairs (mAP 0.965 against
/// 0.970) at a tenth of the time, what a query of 64 shortlisted models needs to stay within 2 ms.
double lightFieldDistance(const std::vector<float>& a, const std::vector<float>& b, int queryFields = 1);
/// The part FLANN indexes: the mean view.
std::vector<float> lightFieldSummary(const std::vector<float>& descriptor);

/// A light field kept at 8 bits per feature, as Chen et al. keep theirs: a feature v as round(255 sqrt v),
/// so the many small features keep their resolution. Outline coefficients over the outline's sum lie in
/// [0, 1]; Zernike magnitudes of a silhouette in the unit disk do in practice (the synthetic set's largest
/// is 0.84), and larger ones are clamped to 1. A quarter of the bytes to read, and distances that are sums
/// of absolute byte differences.
using QuantizedLightField = std::vector<uint8_t>;
QuantizedLightField quantizeLightField(const std::vector<float>& descriptor);
/// The features back (v = (q / 255)^2).
std::vector<float> dequantizeLightField(const QuantizedLightField& descriptor);
/// lightFieldSummary(dequantizeLightField(d)) of kLightFieldLength bytes in place.
std::vector<float> quantizedLightFieldSummary(const uint8_t* descriptor);
/// lightFieldDistance on quantized light fields: L1 of the quantized features over 255 (so on the scale of
/// square roots of the features), least over the same turns.
double lightFieldDistance(const QuantizedLightField& a, const QuantizedLightField& b, int queryFields = 1);
/// The same on kLightFieldLength bytes each (a record in place).
double lightFieldDistance(const uint8_t* a, const uint8_t* b, int queryFields = 1);

/// The 60 rotations of the dodecahedron onto itself, as permutations of the 10 view axes.
const std::vector<std::array<uint8_t, kViewsPerLightField>>& dodecahedronRotations();

} // namespace vdbclay::query
