// SPDX-License-Identifier: Apache-2.0
using System;
using System.Globalization;
using System.Runtime.InteropServices;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>
    /// Number text under a decimal-comma culture and C locale. A SCADA front
    /// end runs with CultureInfo de-DE, where 1.5.ToString() is "1,5"; a
    /// native host may also set the C library's locale to de_DE. Calibration
    /// text saved under one must load under the other with every value
    /// bit-identical (tolerance 0: the writer writes the shortest text that
    /// reads back as the same double), and the binding's own texts write
    /// numbers the same under every culture.
    /// </summary>
    public class LocaleTests
    {
        private static readonly CultureInfo German = CultureInfo.GetCultureInfo("de-DE");

        /// <summary>Fractional values no short decimal writes.</summary>
        private static Calibration Sensor()
        {
            using var reference = Calibration.Reference();
            var calib = new Calibration();
            calib.SetFrameSize(reference.FrameWidth, reference.FrameHeight);
            calib.Intrinsics = new CameraIntrinsics(6 / 0.0055, 6 / 0.0055 + 1.0 / 3, 1023.5 + 1.0 / 7,
                                                    1023.5 - 1.0 / 9, k1: -0.1 / 3, k2: 0.01 / 7);
            for (int laser = 0; laser < Calibration.Lasers; ++laser)
            {
                double[,] h = reference.GetHomography(laser);
                for (int r = 0; r < 3; ++r)
                    for (int c = 0; c < 3; ++c)
                        h[r, c] *= 1 + 1e-3 / 3;
                calib.SetHomography(laser, h);
                calib.SetLaserOffset(laser, laser == 0 ? -50 - 1.0 / 3 : 50 + 1.0 / 7);
            }
            calib.EncoderScale = 0.01 / 3;
            calib.FiberGrid = new FiberGrid(-999.9, 2.0 / 3, 1000);
            calib.Finish();
            return calib;
        }

        private static long[] Bits(Calibration calib)
        {
            var values = new System.Collections.Generic.List<double>();
            CameraIntrinsics i = calib.Intrinsics;
            values.AddRange(new[] { i.Fx, i.Fy, i.Cx, i.Cy, i.K1, i.K2, i.P1, i.P2, i.K3, i.K4, i.K5, i.K6 });
            for (int laser = 0; laser < Calibration.Lasers; ++laser)
            {
                foreach (double v in calib.GetHomography(laser))
                    values.Add(v);
                values.Add(calib.GetLaserOffset(laser));
            }
            values.Add(calib.EncoderScale);
            values.Add(calib.FiberGrid.FirstXMm);
            values.Add(calib.FiberGrid.PitchMm);
            return values.ConvertAll(BitConverter.DoubleToInt64Bits).ToArray();
        }

        private static void AssertNoDecimalComma(string text)
        {
            for (int k = 1; k + 1 < text.Length; ++k)
                Assert.False(text[k] == ',' && char.IsDigit(text[k - 1]) && char.IsDigit(text[k + 1]),
                             "decimal comma at: " + text.Substring(Math.Max(0, k - 10), Math.Min(20, text.Length - Math.Max(0, k - 10))));
        }

        private static T UnderCulture<T>(CultureInfo culture, Func<T> body)
        {
            CultureInfo saved = CultureInfo.CurrentCulture;
            CultureInfo.CurrentCulture = culture;
            try
            {
                return body();
            }
            finally
            {
                CultureInfo.CurrentCulture = saved;
            }
        }

        [Fact]
        public void TheCultureReallyUsesADecimalComma() =>
            Assert.Equal("1,5", UnderCulture(German, () => 1.5.ToString()));

        [Fact]
        public void CalibrationTextRoundTripsAcrossCultures()
        {
            using var calib = Sensor();
            long[] expected = Bits(calib);
            string german = UnderCulture(German, () => calib.ToText());
            AssertNoDecimalComma(german);
            Assert.Contains("1090.9", german);
            using var loadedInvariant = UnderCulture(CultureInfo.InvariantCulture, () => Calibration.Parse(german));
            Assert.Equal(expected, Bits(loadedInvariant));
            string invariant = UnderCulture(CultureInfo.InvariantCulture, () => calib.ToText());
            Assert.Equal(invariant, german);
            using var loadedGerman = UnderCulture(German, () => Calibration.Parse(invariant));
            Assert.Equal(expected, Bits(loadedGerman));
        }

        [Fact]
        public void TheBindingsTextsDoNotFollowTheCulture()
        {
            using var calib = Sensor();
            string intrinsics = UnderCulture(German, () => calib.Intrinsics.ToString());
            Assert.Contains("fx 1090.909090909091", intrinsics);
            AssertNoDecimalComma(intrinsics);
            string grid = UnderCulture(German, () => calib.FiberGrid.ToString());
            Assert.Equal("1000 fibers from x = -999.9 mm every 0.6666666666666666 mm", grid);
            var info = FlatlineOptions.Describe("laser_spacing");
            Assert.Equal(UnderCulture(CultureInfo.InvariantCulture, () => info.ToString()),
                         UnderCulture(German, () => info.ToString()));
        }

        // The C library's locale of the process (glibc: LC_ALL = 6).
        [DllImport("libc", EntryPoint = "setlocale", CharSet = CharSet.Ansi)]
        private static extern IntPtr SetLocale(int category, string locale);

        [Fact]
        public void CalibrationTextRoundTripsAcrossTheCLocale()
        {
            if (!RuntimeInformation.IsOSPlatform(OSPlatform.Linux))
            {
                Console.WriteLine("SKIPPED CalibrationTextRoundTripsAcrossTheCLocale: sets the C locale through glibc (Linux only)");
                return;
            }
            const int LcAll = 6;
            using var calib = Sensor();
            long[] expected = Bits(calib);
            string inC = calib.ToText();
            if (SetLocale(LcAll, "de_DE.UTF-8") == IntPtr.Zero)
            {
                Console.WriteLine("SKIPPED CalibrationTextRoundTripsAcrossTheCLocale: the de_DE.UTF-8 locale is not " +
                                  "installed (Debian: locales, de_DE.UTF-8 in /etc/locale.gen, locale-gen)");
                return;
            }
            try
            {
                string german = calib.ToText();
                Assert.Equal(inC, german);
                using var loaded = Calibration.Parse(inC);
                Assert.Equal(expected, Bits(loaded));
                using var unfinished = new Calibration();
                var error = Assert.ThrowsAny<InvalidArgumentException>(() => unfinished.FiberGrid = new FiberGrid(-999.5, -0.25, 10));
                Assert.Contains("-0.25", error.Message);
            }
            finally
            {
                SetLocale(LcAll, "C");
            }
            using var back = Calibration.Parse(calib.ToText());
            Assert.Equal(expected, Bits(back));
        }
    }
}
