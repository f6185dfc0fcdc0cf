// SPDX-License-Identifier: Apache-2.0
using System;
using System.Threading;
using Xunit;

namespace Flatline.Tests
{
    public class ParallelTests
    {
        [Fact]
        public void TwoThreadsWithTheirOwnReconstructorsMatchSerialRunsBitwise()
        {
            // Two different sheets, as two gauges of one line would see them.
            var sheets = new[]
            {
                Sheet.Measure(Sheet.Waves, 3000, 6, 0.0, 4.0, vibrationSigma: 2.5, seed: 11),
                Sheet.Measure(Sheet.Sine, 2500, 6, 100.0, 5.0, vibrationSigma: 2.5, seed: 12),
            };
            ReconResult Run(Sheet sheet)
            {
                using var recon = new Reconstructor(sheet.Fibers);
                return Sheet.Stream(recon, sheet, 64);
            }
            var serial = new[] { Run(sheets[0]), Run(sheets[1]) };

            var parallel = new ReconResult[2];
            var errors = new Exception[2];
            using var start = new Barrier(2);
            var threads = new Thread[2];
            for (int t = 0; t < 2; ++t)
            {
                int which = t;
                threads[t] = new Thread(() =>
                {
                    try
                    {
                        start.SignalAndWait();
                        parallel[which] = Run(sheets[which]);
                    }
                    catch (Exception e)
                    {
                        errors[which] = e;
                    }
                });
                threads[t].Start();
            }
            foreach (var thread in threads)
                thread.Join();
            Assert.Null(errors[0]);
            Assert.Null(errors[1]);
            for (int t = 0; t < 2; ++t)
            {
                Assert.Equal(sheets[t].Rows, parallel[t].Rows);
                Assert.Equal(serial[t].S, parallel[t].S);
                Sheet.AssertBitwise(serial[t].Z, parallel[t].Z);
                Assert.Equal(serial[t].Flags, parallel[t].Flags);
            }
        }

        [Fact]
        public void ErrorMessagesAreThreadLocal()
        {
            // One thread fails while the other succeeds; each sees its own outcome.
            Exception? failure = null;
            var failing = new Thread(() =>
            {
                try
                {
                    for (int i = 0; i < 200; ++i)
                        Assert.Throws<InvalidArgumentException>(() => new Reconstructor(0));
                }
                catch (Exception e)
                {
                    failure = e;
                }
            });
            failing.Start();
            for (int i = 0; i < 200; ++i)
            {
                using var recon = new Reconstructor(1);
                Assert.Equal(1, recon.Fibers);
            }
            failing.Join();
            Assert.Null(failure);
        }
    }
}
