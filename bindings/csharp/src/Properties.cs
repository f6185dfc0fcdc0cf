// SPDX-License-Identifier: Apache-2.0
using System.Runtime.CompilerServices;

// The tests check internals: the live-handle counters, the status mirror and
// the native path resolution.
[assembly: InternalsVisibleTo("Flatline.Tests")]
