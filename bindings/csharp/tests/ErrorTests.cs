// SPDX-License-Identifier: Apache-2.0
using System;
using System.Linq;
using Xunit;

namespace Flatline.Tests
{
    public class ErrorTests
    {
        [Fact]
        public void PublicStatusMirrorsEveryCodeSwigGeneratedFromTheHeader()
        {
            var native = Enum.GetValues(typeof(NativeStatus)).Cast<NativeStatus>().ToArray();
            Assert.Contains(NativeStatus.FLT_ERR_BUFFER_FULL, native);
            foreach (var code in native)
            {
                Assert.True(Enum.IsDefined(typeof(Status), (int)code), $"Status lacks {code} = {(int)code}");
                Assert.Equal(code.ToString(), Library.StatusName((Status)(int)code));
            }
            Assert.Equal(native.Length, Enum.GetValues(typeof(Status)).Length);
        }

        [Theory]
        [InlineData(Status.InvalidArgument, typeof(InvalidArgumentException))]
        [InlineData(Status.OutOfMemory, typeof(FlatlineOutOfMemoryException))]
        [InlineData(Status.State, typeof(FlatlineStateException))]
        [InlineData(Status.BufferFull, typeof(BufferFullException))]
        [InlineData(Status.IO, typeof(FlatlineIOException))]
        [InlineData(Status.Format, typeof(FlatlineFormatException))]
        [InlineData(Status.Device, typeof(DeviceException))]
        [InlineData(Status.Timeout, typeof(DeviceTimeoutException))]
        [InlineData(Status.NotFound, typeof(NotFoundException))]
        [InlineData(Status.Numeric, typeof(NumericException))]
        [InlineData(Status.Internal, typeof(FlatlineInternalException))]
        [InlineData((Status)(-77), typeof(FlatlineException))]
        public void EachStatusMapsToItsExceptionType(Status status, Type expected)
        {
            Exception e = Errors.Create(status, "the message");
            Assert.Equal(expected, e.GetType());
            Assert.Equal(status, Assert.IsAssignableFrom<IFlatlineException>(e).Status);
            Assert.Equal("the message", e.Message);
        }

        [Fact]
        public void FamiliesCatchTogether()
        {
            Assert.IsAssignableFrom<FlatlineIOException>(Errors.Create(Status.Format, "x"));
            Assert.IsAssignableFrom<DeviceException>(Errors.Create(Status.Timeout, "x"));
            Assert.IsAssignableFrom<FlatlineException>(Errors.Create(Status.Internal, "x"));
            // An empty C message still says what went wrong.
            Assert.Equal("FLT_ERR_STATE", Errors.Create(Status.State, "").Message);
            Assert.Equal("FLT_ERR_STATE", ((IFlatlineException)Errors.Create(Status.State, "")).StatusName);
        }

        [Theory]
        [InlineData(Status.InvalidArgument, typeof(ArgumentException))]
        [InlineData(Status.OutOfMemory, typeof(OutOfMemoryException))]
        [InlineData(Status.State, typeof(InvalidOperationException))]
        [InlineData(Status.BufferFull, typeof(InvalidOperationException))]
        [InlineData(Status.IO, typeof(System.IO.IOException))]
        [InlineData(Status.Format, typeof(System.IO.IOException))]
        [InlineData(Status.Device, typeof(System.IO.IOException))]
        [InlineData(Status.Timeout, typeof(System.IO.IOException))]
        [InlineData(Status.NotFound, typeof(System.Collections.Generic.KeyNotFoundException))]
        [InlineData(Status.Numeric, typeof(ArithmeticException))]
        public void EachIsTheDotNetExceptionOfTheSameMeaning(Status status, Type dotnet)
        {
            // catch (IOException) around a file read, catch (ArgumentException)
            // around a setter: .NET code catches libflatline's failures with
            // the types it already knows.
            Exception e = Errors.Create(status, "x");
            Assert.IsAssignableFrom(dotnet, e);
            Assert.IsAssignableFrom<IFlatlineException>(e);
        }

        [Fact]
        public void ACatchForTheDotNetTypeCatchesARealFailure()
        {
            string missing = System.IO.Path.Combine(System.IO.Path.GetTempPath(), "flatline-no-such-dir", "none.json");
            var io = Assert.ThrowsAny<System.IO.IOException>(() => Calibration.Load(missing));
            Assert.Equal(Status.IO, ((IFlatlineException)io).Status);
            Assert.Contains("none.json", io.Message);
            var arg = Assert.ThrowsAny<ArgumentException>(() => new Reconstructor(0));
            Assert.Equal("FLT_ERR_INVALID_ARGUMENT", ((IFlatlineException)arg).StatusName);
        }

        [Fact]
        public void InvalidArgumentFromTheCLibraryCarriesItsStatusAndMessage()
        {
            var e = Assert.Throws<InvalidArgumentException>(() => new Reconstructor(0));
            Assert.Equal(Status.InvalidArgument, e.Status);
            Assert.Equal("flt_recon_create: argument 'fibers' is 0", e.Message);
        }

        [Fact]
        public void NonIncreasingPositionsAreAnInvalidArgument()
        {
            using var recon = new Reconstructor(2);
            var e = Assert.Throws<InvalidArgumentException>(() =>
                recon.Push(new[] { 10.0, 10.0 }, new double[2, 2], new double[2, 2]));
            Assert.Contains("s[1] = 10 does not increase", e.Message);
            recon.Push(new[] { 10.0, 11.0 }, new double[2, 2], new double[2, 2]);
            e = Assert.Throws<InvalidArgumentException>(() => recon.Push(11.0, new double[2], new double[2]));
            Assert.Contains("s[0] = 11 does not increase", e.Message);
        }

        [Fact]
        public void PullBeforePushIsAStateError()
        {
            using var recon = new Reconstructor(3);
            var e = Assert.Throws<FlatlineStateException>(() => recon.Pull());
            Assert.Equal(Status.State, e.Status);
            Assert.Contains("nothing was pushed", e.Message);
        }

        [Fact]
        public void EndSheetTwiceIsAStateError()
        {
            using var recon = new Reconstructor(1);
            recon.Push(0.0, new[] { 1.0 }, new[] { 0.0 });
            recon.EndSheet();
            var e = Assert.Throws<FlatlineStateException>(() => recon.EndSheet());
            Assert.Contains("no row was pushed since the last end_sheet", e.Message);
        }

        [Fact]
        public void BoundaryBeforeTheFirstEndSheetIsAStateError()
        {
            using var recon = new Reconstructor(1);
            Assert.Throws<FlatlineStateException>(() => recon.Boundary());
        }

        [Fact]
        public void SmallRowCapacityFillsUp()
        {
            using var options = new FlatlineOptions { RowCapacity = 16 };
            using var recon = new Reconstructor(2, options);
            var sheet = Sheet.Measure(Sheet.Waves, 17, 2, 0.0, 5.0);
            var e = Assert.Throws<BufferFullException>(() => recon.Push(sheet.S, sheet.Height, sheet.Slope));
            Assert.Equal(Status.BufferFull, e.Status);
            Assert.Contains("17 rows do not fit", e.Message);
            // Nothing was pushed: 16 rows still fit, then one more does not.
            recon.Push(Sheet.Slice(sheet.S, 0, 16), Sheet.Slice(sheet.Height, 0, 16), Sheet.Slice(sheet.Slope, 0, 16));
            Assert.Throws<BufferFullException>(() => recon.Push(sheet.S[16], new double[2], new double[2]));
        }

        [Fact]
        public void UnknownOptionNameIsNotFound()
        {
            using var options = new FlatlineOptions();
            var e = Assert.Throws<NotFoundException>(() => options.Set("knot_spacingg", 50));
            Assert.Equal(Status.NotFound, e.Status);
            Assert.Contains("knot_spacingg", e.Message);
            Assert.Contains("did you mean 'knot_spacing'?", e.Message);
            using var recon = new Reconstructor(1);
            Assert.Throws<NotFoundException>(() => recon.GetOption("no_such_option"));
        }

        [Fact]
        public void NonAsciiNamesTravelAsUtf8()
        {
            using var options = new FlatlineOptions();
            var e = Assert.Throws<NotFoundException>(() => options.Get("höhe_σ"));
            Assert.Contains("höhe_σ", e.Message);
            Assert.Throws<ArgumentException>(() => options.Get("knot\0spacing"));
        }
    }
}
