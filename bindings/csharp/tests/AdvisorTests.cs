// SPDX-License-Identifier: Apache-2.0
#nullable enable
using System;
using System.IO;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>The leveler advisor: a leveler file and its errors, the advice
    /// against the exact bounded minimiser of a one-actuator problem,
    /// identification of a known G and its refusal.</summary>
    public class AdvisorTests
    {
        private const string Leveler = @"{ ""format"": ""flatline-leveler"", ""version"": 1,
  ""zones"": 3,
  ""actuators"": [
    { ""name"": ""entry gap"", ""unit"": ""mm"", ""min"": -3, ""max"": 3, ""step"": 0.5 },
    { ""name"": ""tilt"", ""unit"": ""mm"", ""min"": -2, ""max"": 2, ""step"": 0.3 } ],
  ""influence"": [ [ 4.0, -6.0 ],
                 [ -8.0, 0.0 ],
                 [ 4.0, 6.0 ] ],
  ""target"": [ 0, 2, 0 ] }";

        [Fact]
        public void LevelerFileAndItsErrors()
        {
            using var a = Advisor.Parse(Leveler);
            Assert.Equal(3, a.Zones);
            Assert.Equal(2, a.Actuators);
            var tilt = a.GetActuator(1);
            Assert.Equal("tilt", tilt.Name);
            Assert.Equal("mm", tilt.Unit);
            Assert.Equal(0.3, tilt.Step);
            Assert.Equal(-8.0, a.GetInfluence()[1, 0]);
            Assert.Equal(1.0, a.Fit.RSquared);
            // The file's target: a profile equal to it (plus a level) needs nothing.
            var advice = a.Advise(new[] { 10.0, 12.0, 10.0 }, new[] { 0.0, 0.0 });
            Assert.True(Math.Abs(advice.Delta[0]) < 1e-12 && Math.Abs(advice.Delta[1]) < 1e-12);

            string path = Path.Combine(Path.GetTempPath(), $"flatline-lévelér-{Guid.NewGuid():N}.json");
            File.WriteAllText(path, Leveler);
            try
            {
                using var loaded = Advisor.Load(path);
                Assert.Equal(3, loaded.Zones);
            }
            finally
            {
                File.Delete(path);
            }
            var e = Assert.Throws<FlatlineFormatException>(() => Advisor.Parse(Leveler.Replace("[ -8.0, 0.0 ]", "[ -8.0 ]")));
            Assert.Contains("'influence[1]' (line 7)", e.Message);
        }

        [Fact]
        public void AdviceIsTheBoundedMinimiser()
        {
            // One actuator: the bounded minimiser is the free one clipped to the
            // box, d = clip(-gain g.r / (g.g (1 + damping)), lo, hi), with g and r
            // without their means.
            using var options = new FlatlineOptions { AdvisorDamping = 0.1, AdvisorGain = 0.5 };
            using var a = new Advisor(4, 1, options);
            a.SetActuator(0, "tilt", "mm", -1.0, 1.0, 0.25);
            a.SetInfluence(new double[,] { { -3 }, { -1 }, { 1 }, { 3 } });
            double[] gc = { -3, -1, 1, 3 };
            foreach (var (p, u) in new[] { (new[] { 0.0, 0, 1, 2 }, 0.0), (new[] { 3.0, 1, 0, 0 }, 0.9) })
            {
                double mean = (p[0] + p[1] + p[2] + p[3]) / 4, gr = 0, gg = 0;
                for (int z = 0; z < 4; ++z)
                {
                    gr += gc[z] * (p[z] - mean);
                    gg += gc[z] * gc[z];
                }
                double free = -0.5 * gr / (gg * 1.1);
                double lo = Math.Max(-1.0 - u, -0.25), hi = Math.Min(1.0 - u, 0.25);
                var advice = a.Advise(p, new[] { u });
                // One division and sums of small integers.
                Assert.True(Math.Abs(advice.Delta[0] - Math.Min(Math.Max(free, lo), hi)) < 1e-12, $"{advice.Delta[0]}");
                Assert.True(u + advice.Delta[0] <= 1.0);
                for (int z = 0; z < 4; ++z)
                    Assert.True(Math.Abs(advice.Predicted[z] - (p[z] + gc[z] * advice.Delta[0])) < 1e-12);
            }
            Assert.Throws<InvalidArgumentException>(() => a.Advise(new[] { 0.0, 0, 0 }, new[] { 0.0 }));
            Assert.Throws<InvalidArgumentException>(() => new FlatlineOptions { AdvisorGain = 0 });
            using var other = new FlatlineOptions { FlatZoneWidth = 100 };
            Assert.Throws<InvalidArgumentException>(() => Advisor.Parse(Leveler, other));
        }

        [Fact]
        public void IdentificationRecoversGAndRefusesNoise()
        {
            var rng = new Random(4);
            const int Z = 12, A = 3, S = 30;
            var g = new double[Z, A];
            for (int z = 0; z < Z; ++z)
                for (int j = 0; j < A; ++j)
                    g[z, j] = rng.NextDouble() * 20 - 10;
            var du = new double[S, A];
            var dp = new double[S, Z];
            for (int k = 0; k < S; ++k)
            {
                for (int j = 0; j < A; ++j)
                    du[k, j] = rng.NextDouble() * 2 - 1;
                for (int z = 0; z < Z; ++z)
                {
                    double v = 0;
                    for (int j = 0; j < A; ++j)
                        v += g[z, j] * du[k, j];
                    dp[k, z] = v; // noise-free: the fit is exact
                }
            }
            using var a = new Advisor(Z, A);
            var fit = a.Identify(du, dp);
            Assert.Equal(S, fit.Steps);
            Assert.True(fit.RSquared > 1 - 1e-12, $"{fit.RSquared}");
            var gid = a.GetInfluence();
            for (int j = 0; j < A; ++j)
            {
                double mean = 0;
                for (int z = 0; z < Z; ++z)
                    mean += g[z, j] / Z;
                // A 3 x 3 normal solve of well-spread steps: ~1e-14 relative.
                for (int z = 0; z < Z; ++z)
                    Assert.True(Math.Abs(gid[z, j] - (g[z, j] - mean)) < 1e-9);
            }
            for (int k = 0; k < S; ++k)
                for (int z = 0; z < Z; ++z)
                    dp[k, z] = rng.NextDouble() * 6 - 3; // unrelated to the steps
            Assert.Throws<NumericException>(() => a.Identify(du, dp));
            Assert.True(a.Fit.RSquared < Advisor.MinRSquared);
            for (int j = 0; j < A; ++j)
                a.SetActuator(j, $"u{j}", "mm", -1, 1, 0.5);
            var e = Assert.Throws<FlatlineStateException>(() => a.Advise(new double[Z], new double[A]));
            Assert.Contains("refused", e.Message);
        }
    }
}
