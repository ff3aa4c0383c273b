// SPDX-License-Identifier: BSD-3-Clause
// The robust range of every point array (and component) of an image: the
// range over which a channel's default transfer functions are spread when
// ParaView first shows it, the same as mcvol-render's "range": "auto"
// (Wrapping/Python/mcvol/scenefile/assemble.py, auto_range): the 0.1 and
// 99.9 percentiles of the finite values (numpy's linear interpolation
// between order statistics; for more than 2^24 finite values of a
// floating-point or 32/64-bit integer array, those of a stratified sample of
// 2^24 of them, within about 1e-5 of the percentile's rank), or min..max
// when the values take at most 256 distinct values (labels, masks) or the
// percentiles coincide.
//
// Under MPI the ranges are those of the whole data set, the same on every
// process and the same as one process gets from the whole image: every
// process takes part with its piece (ParaView's image pieces share their
// boundary planes; each shared point counts once, in the lower piece).
#ifndef mcvolChannelDefaultRanges_h
#define mcvolChannelDefaultRanges_h

#include <string>

class vtkImageData;
class vtkMultiProcessController;

namespace mcvol
{
/// One line per named point array and component: "name\tcomponent\tlo\thi\n"
/// (lo and hi with 17 significant digits); arrays without finite values are
/// left out. With a controller of more than one process the call is
/// collective: every process calls it, with its piece (empty or null when it
/// holds none).
std::string RobustRanges(vtkImageData* image, vtkMultiProcessController* controller = nullptr);
}

#endif
