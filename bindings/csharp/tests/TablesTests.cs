// SPDX-License-Identifier: Apache-2.0
using System;
using System.Linq;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>The enums of keys that bindings/gen_tables.py generates from the
    /// headers agree with SWIG's own reading of the same headers: every C
    /// enumerator is a member of the same value, under its PascalCase name,
    /// and nothing else is.</summary>
    public class TablesTests
    {
        private static string Pascal(string snake) =>
            string.Concat(snake.Split('_').Select(w => w.Substring(0, 1) + w.Substring(1).ToLowerInvariant()));

        private static void AgreesWithTheHeader<TPublic, TNative>(string prefix, int count)
            where TPublic : struct, Enum where TNative : struct, Enum
        {
            var native = Enum.GetNames(typeof(TNative))
                .Where(n => !n.EndsWith("_MAX_ENUM_", StringComparison.Ordinal))
                .ToDictionary(n => Pascal(n.Substring(prefix.Length)),
                              n => Convert.ToInt32(Enum.Parse(typeof(TNative), n)));
            var mine = Enum.GetNames(typeof(TPublic))
                .ToDictionary(n => n, n => Convert.ToInt32(Enum.Parse(typeof(TPublic), n)));
            Assert.Equal(native.OrderBy(kv => kv.Value), mine.OrderBy(kv => kv.Value));
            Assert.Equal(Enumerable.Range(0, count), mine.Values.OrderBy(v => v));
        }

        [Fact]
        public void SheetValuesAreTheHeaders() =>
            AgreesWithTheHeader<SheetValue, NativeSheetValue>("FLT_SHEET_", Tables.SheetValueCount);

        [Fact]
        public void GaugeCountersAreTheHeaders() =>
            AgreesWithTheHeader<GaugeCounter, NativeGaugeCounter>("FLT_GAUGE_COUNT_", Tables.GaugeCounterCount);
    }
}
