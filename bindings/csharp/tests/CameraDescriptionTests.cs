// SPDX-License-Identifier: Apache-2.0
using System;
using System.IO;
using System.IO.Compression;
using System.Text;
using Xunit;

namespace Flatline.Tests
{
    /// <summary>The offline view of a camera description: a description
    /// written here, evaluated against register bytes put into the memory
    /// image (each value worked out by hand from the bytes), a zipped file,
    /// and the errors.</summary>
    public class CameraDescriptionTests
    {
        private const string Xml = @"<?xml version=""1.0"" encoding=""utf-8""?>
<RegisterDescription VendorName=""Flatline"" ModelName=""NetCam"" SchemaMajorVersion=""1""
    SchemaMinorVersion=""1"" SchemaSubMinorVersion=""0"">
  <Category Name=""Root""><pFeature>ImageFormat</pFeature><pFeature>TriggerMode</pFeature>
    <pFeature>Ghost</pFeature></Category>
  <Category Name=""ImageFormat""><pFeature>Width</pFeature><pFeature>PayloadSize</pFeature></Category>
  <Category Name=""Empty""></Category>
  <Integer Name=""Width""><pValue>WidthReg</pValue><Min>16</Min><Max>4096</Max><Inc>16</Inc></Integer>
  <IntReg Name=""WidthReg""><Address>0x100</Address><Length>4</Length><AccessMode>RW</AccessMode>
    <pPort>Device</pPort><Sign>Unsigned</Sign><Endianess>LittleEndian</Endianess></IntReg>
  <Converter Name=""ExposureTime""><FormulaTo>FROM / 1.024</FormulaTo><FormulaFrom>TO * 1.024</FormulaFrom>
    <pValue>ExposureRaw</pValue><Unit>us</Unit></Converter>
  <IntReg Name=""ExposureRaw""><Address>0x104</Address><Length>4</Length><AccessMode>RW</AccessMode>
    <pPort>Device</pPort><Sign>Unsigned</Sign><Endianess>LittleEndian</Endianess></IntReg>
  <Enumeration Name=""TriggerMode""><EnumEntry Name=""Off""><Value>0</Value></EnumEntry>
    <EnumEntry Name=""On""><Value>1</Value></EnumEntry><pValue>TriggerReg</pValue></Enumeration>
  <IntReg Name=""TriggerReg""><Address>0x108</Address><Length>4</Length><AccessMode>RW</AccessMode>
    <pPort>Device</pPort><Sign>Unsigned</Sign><Endianess>LittleEndian</Endianess></IntReg>
  <Command Name=""AcquisitionStart""><pValue>StartReg</pValue><CommandValue>1</CommandValue></Command>
  <IntReg Name=""StartReg""><Address>0x10C</Address><Length>4</Length><AccessMode>WO</AccessMode>
    <pPort>Device</pPort><Endianess>LittleEndian</Endianess></IntReg>
  <IntSwissKnife Name=""PayloadSize""><pVariable Name=""W"">Width</pVariable><Formula>W * 480</Formula></IntSwissKnife>
</RegisterDescription>";

        private static CameraDescription Loaded()
        {
            var c = CameraDescription.FromBytes(Encoding.UTF8.GetBytes(Xml));
            c.SetMemory(0x100, BitConverter.GetBytes(640u)); // Width, little endian
            c.SetMemory(0x104, BitConverter.GetBytes(1000u)); // ExposureRaw
            c.SetMemory(0x108, BitConverter.GetBytes(1u)); // TriggerMode On
            return c;
        }

        [Fact]
        public void ListsFeaturesWithTheirDeclarations()
        {
            using var c = Loaded();
            Assert.Equal("Flatline", c.Vendor);
            Assert.Equal("NetCam", c.Model);
            Assert.Equal("1.1.0", c.SchemaVersion);
            Assert.Equal(9, c.FeatureNames.Count);
            Assert.True(c.Contains("Width"));
            Assert.False(c.Contains("Nope"));
            var exposure = c.GetFeature("ExposureTime");
            Assert.Equal(FeatureType.Float, exposure.Type);
            Assert.Equal("Converter", exposure.Kind);
            Assert.Equal("us", exposure.Unit);
            Assert.Equal(FeatureType.Enumeration, c.GetFeature("TriggerMode").Type);
            Assert.Equal(FeatureType.Command, c.GetFeature("AcquisitionStart").Type);
        }

        [Fact]
        public void WalksTheFeatureTree()
        {
            using var c = Loaded();
            // the file's order; "Ghost" names no node
            Assert.Equal(new[] { "ImageFormat", "TriggerMode", "Ghost" }, c.GetCategory());
            Assert.Equal(new[] { "Width", "PayloadSize" }, c.GetCategory("ImageFormat"));
            Assert.Empty(c.GetCategory("Empty"));
            Assert.Equal(FeatureType.Category, c.GetFeature("ImageFormat").Type);
            Assert.Contains("no category", Assert.Throws<NotFoundException>(() => c.GetCategory("Width")).Message);
            Assert.Contains("no category", Assert.Throws<NotFoundException>(() => c.GetCategory("Nope")).Message);
            Assert.Throws<ArgumentNullException>(() => c.GetCategory(null!));
            // categories are not features
            Assert.False(c.Contains("ImageFormat"));
            Assert.Equal(9, c.FeatureNames.Count);
        }

        [Fact]
        public void EvaluatesFeaturesForTheRegisters()
        {
            using var c = Loaded();
            Assert.Equal(640, c.GetInt("Width"));
            Assert.Equal(640 * 480, c.GetInt("PayloadSize"));
            // 1000 counts * 1.024 us: 1024 to one rounding of a double
            Assert.Equal(1024.0, c.GetFloat("ExposureTime"), 9);
            Assert.Equal("On", c.GetString("TriggerMode"));
            var register = c.GetRegister("ExposureTime");
            Assert.Equal(0x104UL, register.Address);
            Assert.Equal(4, register.Length);
            Assert.Equal(0, register.Lsb);
            Assert.Equal(31, register.Msb);
            Assert.False(register.BigEndian);
            Assert.Equal((16L, 4096L, 16L), c.GetIntBounds("Width"));
            var entries = c.GetEntries("TriggerMode");
            Assert.Equal(2, entries.Count);
            Assert.Equal("On", entries[1].Name);
            Assert.Equal(1, entries[1].Value);
            Assert.True(entries[1].Available);
            Assert.Equal(FeatureAccess.ReadWrite, c.GetAccess("Width"));
            Assert.Equal(FeatureAccess.WriteOnly, c.GetAccess("AcquisitionStart"));
            Assert.Equal(FeatureAccess.ReadOnly, c.GetAccess("PayloadSize"));
            Assert.Equal((true, true, false), c.GetFlags("Width"));
        }

        [Fact]
        public void WritesLandInTheMemoryImage()
        {
            using var c = Loaded();
            c.SetInt("Width", 800);
            Assert.Equal(800u, BitConverter.ToUInt32(c.GetMemory(0x100, 4), 0));
            // 1000 us / 1.024 = 976.5625 counts: the nearest, 977
            c.SetFloat("ExposureTime", 1000.0);
            Assert.Equal(977u, BitConverter.ToUInt32(c.GetMemory(0x104, 4), 0));
            c.SetString("TriggerMode", "Off");
            Assert.Equal(0u, BitConverter.ToUInt32(c.GetMemory(0x108, 4), 0));
            c.Execute("AcquisitionStart");
            Assert.Equal(1u, BitConverter.ToUInt32(c.GetMemory(0x10C, 4), 0));
            c.ClearMemory();
            Assert.Throws<NotFoundException>(() => c.GetInt("Width"));
        }

        [Fact]
        public void ErrorsNameTheProblem()
        {
            using var c = Loaded();
            var outside = Assert.Throws<InvalidArgumentException>(() => c.SetInt("Width", 8192));
            Assert.Contains("outside 16 .. 4096", outside.Message);
            Assert.Contains("multiple of 16", Assert.Throws<InvalidArgumentException>(() => c.SetInt("Width", 650)).Message);
            Assert.Contains("read-only", Assert.Throws<FlatlineStateException>(() => c.SetInt("PayloadSize", 1)).Message);
            Assert.Contains("'Nope'", Assert.Throws<NotFoundException>(() => c.GetInt("Nope")).Message);
            Assert.Contains("no single register", Assert.Throws<NotFoundException>(() => c.GetRegister("PayloadSize")).Message);
            Assert.Contains("no entry 'Maybe'", Assert.Throws<NotFoundException>(() => c.SetString("TriggerMode", "Maybe")).Message);
            Assert.Throws<ArgumentNullException>(() => c.GetInt(null!));  // null on purpose: the check under test
            Assert.Throws<ArgumentException>(() => c.SetMemory(0, Array.Empty<byte>()));
            Assert.Contains("malformed", Assert.Throws<FlatlineFormatException>(
                () => CameraDescription.FromBytes(Encoding.UTF8.GetBytes(Xml.Substring(0, 200)))).Message);
            Assert.Throws<FlatlineIOException>(() => CameraDescription.Load("/nonexistent/camera.xml"));
            c.SetInt("Width", 32); // the handle stays usable
            Assert.Equal(32, c.GetInt("Width"));
            c.Dispose();
            Assert.Throws<ObjectDisposedException>(() => c.GetInt("Width"));
        }

        [Fact]
        public void LoadsAZippedFile()
        {
            string path = Path.Combine(Path.GetTempPath(), $"flatline-genicam-{Guid.NewGuid():N}.zip");
            try
            {
                using (var zip = ZipFile.Open(path, ZipArchiveMode.Create))
                {
                    var entry = zip.CreateEntry("camera.xml", CompressionLevel.Optimal);
                    using var stream = entry.Open();
                    var bytes = Encoding.UTF8.GetBytes(Xml);
                    stream.Write(bytes, 0, bytes.Length);
                }
                using var c = CameraDescription.Load(path);
                Assert.Equal("NetCam", c.Model);
                Assert.Equal(9, c.FeatureNames.Count);
            }
            finally
            {
                File.Delete(path);
            }
        }
    }
}
