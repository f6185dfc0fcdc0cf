// SPDX-License-Identifier: Apache-2.0
using Xunit;

namespace Flatline.Tests
{
    /// <summary>Frames where a test expects one: <see cref="FrameSource.Next"/>
    /// returns null only at the end of images, and a frame carries
    /// <see cref="Frame.Pixels8"/> or <see cref="Frame.Pixels16"/> by its
    /// format; these fail the test instead of passing a null on.</summary>
    internal static class Frames
    {
        /// <summary>The next frame, which must come.</summary>
        public static Frame Take(this FrameSource source, int timeoutMs = 1000, Frame? reuse = null)
        {
            Frame? frame = source.Next(timeoutMs, reuse);
            Assert.NotNull(frame);
            return frame;
        }

        /// <summary>The pixels of a Mono8 frame.</summary>
        public static byte[,] Mono8(this Frame frame) => Assert.IsType<byte[,]>(frame.Pixels);

        /// <summary>The pixels of a Mono10/12/16 frame.</summary>
        public static ushort[,] Mono16(this Frame frame) => Assert.IsType<ushort[,]>(frame.Pixels);

        /// <summary>The pixels of a simulated Mono8 frame.</summary>
        public static byte[,] Mono8(this SimulatedFrame frame) => Assert.IsType<byte[,]>(frame.Pixels);

        /// <summary>The pixels of a simulated Mono10/12/16 frame.</summary>
        public static ushort[,] Mono16(this SimulatedFrame frame) => Assert.IsType<ushort[,]>(frame.Pixels);
    }
}
