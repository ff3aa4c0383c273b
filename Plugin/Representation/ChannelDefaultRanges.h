// SPDX-License-Identifier: BSD-3-Clause
// The robust range of every point array (and component) of an image: the
// range over which a channel's default transfer functions are spread when
// ParaView first shows it, the same as mcvol-render's "range": "auto"
// (Wrapping/Python/mcvol/scenefile/assemble.py, auto_range): the 0.1 and
// 99.9 percentiles of the finite values (numpy's linear interpolation
// between order statistics; of floating-point and 32/64-bit integer arrays
// of more than 2^24 values, those of a stratified sample of 2^24 of them,
// within about 1e-5 of the percentile's rank), or min..max when the values take at most 256
// distinct values (labels, masks) or the percentiles coincide.
#ifndef mcvolChannelDefaultRanges_h
#define mcvolChannelDefaultRanges_h

#include <string>

class vtkDataArray;
class vtkImageData;

namespace mcvol
{
/// [lo, hi] of component `component` of `array`; false when no value is finite.
bool RobustRange(vtkDataArray* array, int component, double range[2]);

/// One line per named point array and component: "name\tcomponent\tlo\thi\n"
/// (lo and hi with 17 significant digits); arrays without finite values are left out.
std::string RobustRanges(vtkImageData* image);
}

#endif
