// SPDX-License-Identifier: Apache-2.0
using System;
using System.IO;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>Verdicts: the straightedge deviation against its closed form,
    /// rule files and their errors, a sheet judged by band.</summary>
    public class VerdictTests
    {
        private const string Rules = @"{
  ""format"": ""flatline-tolerances"", ""version"": 1, ""name"": ""C# test"",
  ""rules"": [
    { ""name"": ""1 m along"", ""measure"": ""straightedge_along"", ""length_mm"": 1000,
      ""bands"": [ { ""thickness_mm"": [1, 3], ""width_mm"": [0, 2000], ""limit"": 3 },
                 { ""thickness_mm"": [3, 6], ""width_mm"": [0, 2000], ""limit"": 5 } ] },
    { ""name"": ""250 mm along"", ""measure"": ""straightedge_along"", ""length_mm"": 250,
      ""bands"": [ { ""thickness_mm"": [1, 6], ""width_mm"": [0, 2000], ""limit"": 0.5 } ] },
    { ""name"": ""bow"", ""measure"": ""bow"",
      ""bands"": [ { ""thickness_mm"": [1, 6], ""width_mm"": [0, 2000], ""limit"": 2 } ] }
  ]
}";

        // A straightedge of length L <= P rests on the points L/2 either side
        // of a trough: A (1 - cos(pi L / P)); a longer one bridges two crests: 2 A.
        private static double SineDeviation(double a, double p, double l) =>
            l >= p ? 2 * a : a * (1 - Math.Cos(Math.PI * l / p));

        [Theory]
        [InlineData(100.0)]
        [InlineData(400.0)]
        [InlineData(500.0)]
        [InlineData(1200.0)]
        public void SineUnderAStraightedge(double length)
        {
            var p = new double[3001];
            var z = new double[p.Length];
            for (int i = 0; i < p.Length; ++i)
            {
                p[i] = i; // troughs and contacts on samples
                z[i] = 2.0 * Math.Cos(2 * Math.PI * i / 500.0);
            }
            var (d, at) = Verdict.Straightedge(p, z, length);
            // cos()'s rounding on heights of 2 mm.
            Assert.True(Math.Abs(d - SineDeviation(2.0, 500.0, length)) < 1e-12, $"{d}");
            Assert.True(Math.Abs(2.0 * Math.Cos(2 * Math.PI * at / 500.0) + 2.0) < 1e-12, $"at {at}");
            Assert.Throws<InvalidArgumentException>(() => Verdict.Straightedge(p, z, 0.0));
        }

        [Fact]
        public void RuleFilesAndTheirErrors()
        {
            using var rules = ToleranceRules.Parse(Rules);
            Assert.Equal(3, rules.Rules.Count);
            Assert.Equal("250 mm along", rules.Rules[1].Name);
            Assert.Equal(Measure.StraightedgeAlong, rules.Rules[1].Measure);
            Assert.Equal(250.0, rules.Rules[1].LengthMm);
            Assert.Equal(Measure.Bow, rules.Rules[2].Measure);
            string path = Path.Combine(Path.GetTempPath(), $"flatline-rules-{Guid.NewGuid():N}.json");
            File.WriteAllText(path, Rules);
            try
            {
                using var loaded = ToleranceRules.Load(path);
                Assert.Equal(3, loaded.Rules.Count);
            }
            finally
            {
                File.Delete(path);
            }
            var e = Assert.Throws<FlatlineFormatException>(() => ToleranceRules.Parse(Rules.Replace("[3, 6]", "[2, 6]")));
            Assert.Contains("'rules[0].bands[1]' (line 6) overlaps", e.Message);
            e = Assert.Throws<FlatlineFormatException>(() => ToleranceRules.Parse(Rules.Replace("\"bow\",", "\"sag\",")));
            Assert.Contains("'rules[2].measure' = \"sag\"", e.Message);
        }

        [Fact]
        public void SheetJudgedByBand()
        {
            const int rows = 3001, fibers = 11;
            var s = new double[rows];
            var x = new double[fibers];
            var z = new double[rows, fibers];
            for (int k = 0; k < fibers; ++k)
                x[k] = -750 + 150.0 * k;
            for (int r = 0; r < rows; ++r)
            {
                s[r] = r;
                for (int k = 0; k < fibers; ++k)
                    z[r, k] = 1.2 * Math.Cos(2 * Math.PI * r / 800.0); // a 1.2 mm wave of 800 mm
            }
            using var rules = ToleranceRules.Parse(Rules);
            using var verdict = new Verdict(rules);
            verdict.SetMeasure(Measure.Bow, -2.5, 0, 1500);
            var results = verdict.Evaluate(2.0, 1500.0, s, x, z);
            // 1 m bridges the wave: 2.4 mm of 3 (band 0). Tolerances: cos()'s rounding.
            Assert.Equal(VerdictState.Pass, results[0].State);
            Assert.Equal(0, results[0].Band);
            Assert.True(Math.Abs(results[0].Worst - 2.4) < 1e-12);
            Assert.True(Math.Abs(results[0].Margin - 0.6) < 1e-12);
            // 250 mm dips into it: 1.2 (1 - cos(pi 250 / 800)) = 0.595 > 0.5.
            Assert.Equal(VerdictState.Fail, results[1].State);
            Assert.True(Math.Abs(results[1].Worst - SineDeviation(1.2, 800, 250)) < 1e-12);
            // |bow| 2.5 > 2, at the position given.
            Assert.Equal(VerdictState.Fail, results[2].State);
            Assert.Equal(2.5, results[2].Worst);
            Assert.Equal(1500.0, results[2].SMm);
            Assert.Equal(2, verdict.Failed);
            // 4 mm: band 1 (limit 5); no map: the straightedges are not measured.
            verdict.SetMeasure(Measure.Bow, double.NaN);
            results = verdict.Evaluate(4.0, 1500.0);
            Assert.Equal(VerdictState.NotMeasured, results[0].State);
            Assert.Equal(5.0, results[0].Limit);
            Assert.True(double.IsNaN(results[0].Worst));
            Assert.Equal(VerdictState.NotMeasured, results[2].State);
            Assert.Equal(0, verdict.Failed);
            // Wider than every band.
            foreach (var r in verdict.Evaluate(2.0, 2500.0))
                Assert.Equal(VerdictState.NoBand, r.State);
            Assert.Throws<InvalidArgumentException>(() => verdict.Evaluate(-1.0, 1500.0, s, x, z));
            Assert.Throws<ArgumentException>(() => verdict.Evaluate(2.0, 1500.0, s, new double[3], z));
        }
    }
}
