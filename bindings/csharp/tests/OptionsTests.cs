// SPDX-License-Identifier: Apache-2.0
using System;
using System.Linq;
using Xunit;

namespace Flatline.Tests
{
    public class OptionsTests
    {
        private static readonly string[] ReconOptions =
        {
            "knot_spacing", "laser_spacing", "height_sigma", "slope_sigma",
            "curvature_weight", "lag_knots", "max_gap", "row_capacity",
        };

        [Fact]
        public void AvailableListsEveryKeyOfTheCLibraryWithItsBounds()
        {
            var keys = FlatlineOptions.Available;
            foreach (string name in ReconOptions)
                Assert.Contains(keys, k => k.Name == name);
            Assert.Equal(keys.Count, keys.Select(k => k.Name).Distinct().Count());
            var lag = keys.Single(k => k.Name == "lag_knots");
            Assert.True(lag.IsInteger);
            Assert.Equal(-1.0, lag.Default);  // derived from latency_mm
            Assert.Equal(2000.0, keys.Single(k => k.Name == "latency_mm").Default);
            var laser = FlatlineOptions.Describe("laser_spacing");
            Assert.False(laser.IsInteger);
            Assert.Equal(100.0, laser.Default);
            Assert.True(laser.Min <= laser.Default && laser.Default <= laser.Max);
        }

        [Fact]
        public void ANewBagHoldsTheDefaults()
        {
            using var options = new FlatlineOptions();
            foreach (var key in FlatlineOptions.Available)
                Assert.Equal(key.Default, options[key.Name]);
            Assert.Equal(0.0, options.KnotSpacing);
            Assert.Equal(100.0, options.LaserSpacing);
            Assert.Equal(2.5, options.HeightSigma);
            Assert.Equal(0.001, options.SlopeSigma);
            Assert.Equal(1e-3, options.CurvatureWeight);
            Assert.Equal(10.0, options.CurvatureJumpWeight);
            Assert.Equal(-1, options.LagKnots);
            Assert.Equal(2000.0, options.LatencyMm);
            Assert.Equal(200.0, options.MaxGap);
            Assert.Equal(8192, options.RowCapacity);
            Assert.False(options.RigidMotion);
            Assert.Equal(0.1, options.ShapeSigma);
            Assert.Equal(RobustMode.None, options.Robust);
            Assert.Equal(2, options.RobustIterations);
            Assert.Equal(8, options.RobustLineIterations);
        }

        [Fact]
        public void TypedPropertiesAndNamesSetTheSameValues()
        {
            using var options = new FlatlineOptions
            {
                KnotSpacing = 50, LaserSpacing = 120, HeightSigma = 1.5, SlopeSigma = 0.002,
                CurvatureWeight = 0.01, LagKnots = 16, MaxGap = 300, RowCapacity = 1000,
                Robust = RobustMode.Huber, RobustIterations = 3, RobustLineIterations = 5,
            };
            Assert.Equal(50.0, options["knot_spacing"]);
            Assert.Equal(120.0, options.Get("laser_spacing"));
            Assert.Equal(1.5, options["height_sigma"]);
            Assert.Equal(0.002, options["slope_sigma"]);
            Assert.Equal(0.01, options["curvature_weight"]);
            Assert.Equal(16.0, options["lag_knots"]);
            Assert.Equal(300.0, options["max_gap"]);
            Assert.Equal(1000.0, options["row_capacity"]);
            Assert.Equal(1.0, options["robust"]);
            Assert.Equal(3.0, options["robust_iterations"]);
            Assert.Equal(5.0, options["robust_line_iterations"]);
            options["max_gap"] = 250;
            Assert.Equal(250.0, options.MaxGap);
            Assert.Same(options, options.Set("lag_knots", 8));
            Assert.Equal(8, options.LagKnots);
        }

        [Fact]
        public void EveryTypedPropertyNamesAKeyOfTheCLibraryAndReadsItsDefault()
        {
            // A typo in a property's C name would throw NotFoundException here.
            using var options = new FlatlineOptions();
            var properties = typeof(FlatlineOptions).GetProperties()
                .Where(p => p.CanRead && p.CanWrite && p.GetIndexParameters().Length == 0).ToArray();
            Assert.True(properties.Length >= 44, $"{properties.Length} typed properties");
            foreach (var property in properties)
            {
                object? value = property.GetValue(options);
                property.SetValue(options, value);  // the default round-trips through the setter
                Assert.Equal(value, property.GetValue(options));
            }
            Assert.Equal(8, options.SimBitDepth);
            Assert.Equal(1u, options.SimSeed);
            Assert.Equal(11, options.ExtractSgWindow);
            Assert.False(options.CalibRansac);
            Assert.Equal(1000, options.CalibRansacIterations);
        }

        [Fact]
        public void RejectedValuesLeaveTheBagUnchanged()
        {
            using var options = new FlatlineOptions { HeightSigma = 2.0 };
            Assert.Throws<InvalidArgumentException>(() => options.HeightSigma = double.NaN);
            Assert.Throws<InvalidArgumentException>(() => options.Set("lag_knots", 2.5));
            var info = FlatlineOptions.Describe("height_sigma");
            Assert.Throws<InvalidArgumentException>(() => options.HeightSigma = info.Min - 1);
            Assert.Equal(2.0, options.HeightSigma);
            Assert.Equal(-1, options.LagKnots);
            Assert.Equal(2000.0, options.LatencyMm);
        }

        [Fact]
        public void AReconstructorCopiesTheOptionsAndReportsTheEffectiveValues()
        {
            var options = new FlatlineOptions { LaserSpacing = 80, LagKnots = 12 };
            using var recon = new Reconstructor(2, options);
            options.Dispose();  // the reconstructor kept its own copy
            Assert.Equal(80.0, recon.GetOption("laser_spacing"));
            Assert.Equal(80.0, recon.GetOption("knot_spacing"));  // 0 resolves to laser_spacing
            Assert.Equal(12.0, recon.GetOption("lag_knots"));
            Assert.Equal(8192.0, recon.GetOption("row_capacity"));
        }

        [Fact]
        public void ChoiceEnumsCarryTheCLibrarysValuesAndNames()
        {
            // The library names each value ("huber"); the C# enum member of
            // that value has the same name, without the underscores.
            void Agree<T>(string option) where T : struct, Enum
            {
                var choices = FlatlineOptions.Describe(option).Choices;
                Assert.Equal(Enum.GetValues(typeof(T)).Length, choices.Count);
                foreach (var pair in choices)
                    Assert.Equal(pair.Key.Replace("_", ""), Enum.GetName(typeof(T), pair.Value), ignoreCase: true);
            }
            Agree<RobustMode>("robust");
            Agree<FlatReference>("flat_reference");
            Agree<EncoderMode>("source_encoder_mode");
            Agree<SimSurround>("sim_surround");
            Agree<DriveSide>("flat_drive_side");
            Agree<ZonesOn>("flat_zones_on");
            Assert.Empty(FlatlineOptions.Describe("max_gap").Choices);
            using var options = new FlatlineOptions
            {
                Robust = RobustMode.Tukey, FlatReference = FlatReference.Mean,
                SourceEncoderMode = EncoderMode.Chunk,
            };
            Assert.Equal(2.0, options["robust"]);
            Assert.Equal(1.0, options["flat_reference"]);
            Assert.Equal(3.0, options["source_encoder_mode"]);
        }

        [Fact]
        public void AnOptionOfAnotherComponentIsRefusedAndAnUnknownOneIsNotFound()
        {
            // One bag for two components: the flatness key would do nothing
            // in the reconstructor, so the reconstructor refuses it.
            using var mixed = new FlatlineOptions { LagKnots = 8, FlatReference = FlatReference.Mean };
            var e = Assert.Throws<InvalidArgumentException>(() => new Reconstructor(2, mixed));
            Assert.Contains("'flat_reference' belongs to flatness, not to the reconstructor", e.Message);
            using var recon = new Reconstructor(2);
            e = Assert.Throws<InvalidArgumentException>(() => recon.GetOption("sim_seed"));
            Assert.Contains("'sim_seed' belongs to the simulator", e.Message);
            // An unknown name is not found by every call alike.
            Assert.Throws<NotFoundException>(() => mixed.Set("no_such_option", 1));
            Assert.Throws<NotFoundException>(() => mixed.Get("no_such_option"));
            Assert.Throws<NotFoundException>(() => FlatlineOptions.Describe("no_such_option"));
            Assert.Throws<NotFoundException>(() => recon.GetOption("no_such_option"));
        }

        [Fact]
        public void DisposeIsImmediateIdempotentAndFinal()
        {
            Finalizers.Settle();
            long before = OptionsHandle.Live;
            var options = new FlatlineOptions();
            Assert.Equal(before + 1, OptionsHandle.Live);
            options.Dispose();
            Assert.Equal(before, OptionsHandle.Live);
            options.Dispose();
            Assert.Equal(before, OptionsHandle.Live);
            Assert.Throws<ObjectDisposedException>(() => options.Get("max_gap"));
            Assert.Throws<ObjectDisposedException>(() => options.MaxGap = 10);
            Assert.Throws<ObjectDisposedException>(() => new Reconstructor(1, options));
        }
    }
}
