// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;

namespace Flatline
{
    /// <summary>The interface a GenICam feature offers (flt_genicam_type).</summary>
    public enum FeatureType
    {
        /// <summary>Integer, IntReg, MaskedIntReg, StructEntry, IntConverter, IntSwissKnife.</summary>
        Integer = NativeGenICamType.FLT_GENICAM_INTEGER,
        /// <summary>Float, FloatReg, Converter, SwissKnife.</summary>
        Float = NativeGenICamType.FLT_GENICAM_FLOAT,
        /// <summary>An entry name over an integer.</summary>
        Enumeration = NativeGenICamType.FLT_GENICAM_ENUMERATION,
        Boolean = NativeGenICamType.FLT_GENICAM_BOOLEAN,
        Command = NativeGenICamType.FLT_GENICAM_COMMAND,
        /// <summary>String, StringReg.</summary>
        String = NativeGenICamType.FLT_GENICAM_STRING,
        /// <summary>Raw bytes.</summary>
        Register = NativeGenICamType.FLT_GENICAM_REGISTER,
        /// <summary>A node of the feature tree (no value): <see cref="CameraDescription.GetCategory"/>.</summary>
        Category = NativeGenICamType.FLT_GENICAM_CATEGORY,
    }

    /// <summary>A feature's access mode for the current register contents (flt_genicam_access).</summary>
    public enum FeatureAccess
    {
        NotImplemented = NativeGenICamAccess.FLT_GENICAM_NOT_IMPLEMENTED,
        NotAvailable = NativeGenICamAccess.FLT_GENICAM_NOT_AVAILABLE,
        WriteOnly = NativeGenICamAccess.FLT_GENICAM_WRITE_ONLY,
        ReadOnly = NativeGenICamAccess.FLT_GENICAM_READ_ONLY,
        ReadWrite = NativeGenICamAccess.FLT_GENICAM_READ_WRITE,
    }

    /// <summary>A feature as the description declares it.</summary>
    public sealed class FeatureInfo
    {
        internal FeatureInfo(string name, FeatureType type, string kind, string unit)
        {
            Name = name;
            Type = type;
            Kind = kind;
            Unit = unit;
        }

        public string Name { get; }
        public FeatureType Type { get; }
        /// <summary>The XML element: "IntReg", "Converter", "StructEntry", ...</summary>
        public string Kind { get; }
        /// <summary>Its Unit ("us", "dB"), "" if none.</summary>
        public string Unit { get; }
        public override string ToString() => $"{Name} ({Kind}, {Type})";
    }

    /// <summary>The register holding a feature's value.</summary>
    public sealed class FeatureRegister
    {
        internal FeatureRegister(ulong address, uint length, uint lsb, uint msb, bool bigEndian)
        {
            Address = address;
            Length = (int)length;
            Lsb = (int)lsb;
            Msb = (int)msb;
            BigEndian = bigEndian;
        }

        /// <summary>Bytes.</summary>
        public ulong Address { get; }
        /// <summary>Bytes.</summary>
        public int Length { get; }
        /// <summary>Lowest bit of the value (0 = the register value's least significant bit).</summary>
        public int Lsb { get; }
        /// <summary>Highest bit of the value.</summary>
        public int Msb { get; }
        public bool BigEndian { get; }
        public override string ToString() =>
            $"0x{Address:x} ({Length} bytes, bits {Lsb}..{Msb}, {(BigEndian ? "big" : "little")} endian)";
    }

    /// <summary>An entry of an enumeration.</summary>
    public sealed class EnumEntryInfo
    {
        internal EnumEntryInfo(string name, long value, bool available)
        {
            Name = name;
            Value = value;
            Available = available;
        }

        public string Name { get; }
        public long Value { get; }
        /// <summary>Implemented and available now.</summary>
        public bool Available { get; }
    }

    /// <summary>
    /// The offline view of a camera description (include/flatline/genicam.h):
    /// a GenICam XML file (or a ZIP archive holding it) loaded without a
    /// camera, with a memory image of the camera's registers. Lists the
    /// features and evaluates them for the register bytes given with
    /// <see cref="SetMemory"/>, the way the library's camera clients do on
    /// a real camera.
    /// </summary>
    /// <remarks>
    /// Reads ignore the access mode (they show what the registers hold);
    /// <see cref="GetAccess"/> says whether a camera would let a feature be
    /// read or written. Writes honour it and land in the memory image.
    /// Errors: <see cref="NotFoundException"/> for a feature the description
    /// lacks or a register byte the image lacks, <see cref="FlatlineFormatException"/>
    /// for a description that is wrong, <see cref="NumericException"/>
    /// for a formula that fails for these registers, <see cref="FlatlineStateException"/>
    /// when the access mode forbids a write. Not thread-safe: one thread at a time.
    /// </remarks>
    public sealed class CameraDescription : IDisposable
    {
        private readonly GenICamHandle handle;
        private readonly List<string> names = new List<string>();

        static CameraDescription() => NativeLoader.EnsureLoaded();

        private CameraDescription(GenICamHandle handle)
        {
            this.handle = handle;
            handle.Track(0);
            FlatlineNative.flt_genicam_feature_count(handle, out UIntPtr count);
            unsafe
            {
                for (ulong i = 0; i < count.ToUInt64(); ++i)
                {
                    IntPtr name;
                    FlatlineNative.flt_genicam_feature_name(handle, i, &name);
                    names.Add(Utf8.Decode(name));
                }
            }
        }

        /// <summary>Loads a description file (XML, or a ZIP archive holding it).</summary>
        public static CameraDescription Load(string path)
        {
            if (path == null)
                throw new ArgumentNullException(nameof(path));
            NativeLoader.EnsureLoaded();
            FlatlineNative.flt_genicam_load(path, out GenICamHandle handle);
            return new CameraDescription(handle);
        }

        /// <summary>Loads a description from its bytes (XML or ZIP).</summary>
        public static unsafe CameraDescription FromBytes(byte[] data)
        {
            if (data == null)
                throw new ArgumentNullException(nameof(data));
            if (data.Length == 0)
                throw new ArgumentException("data is empty", nameof(data));
            NativeLoader.EnsureLoaded();
            GenICamHandle handle;
            fixed (byte* pd = data)
            {
                FlatlineNative.flt_genicam_load_memory(pd, (ulong)data.Length, out handle);
            }
            return new CameraDescription(handle);
        }

        /// <summary>VendorName of the description.</summary>
        public string Vendor => Text(NativeGenICamText.FLT_GENICAM_VENDOR_NAME);
        /// <summary>ModelName of the description.</summary>
        public string Model => Text(NativeGenICamText.FLT_GENICAM_MODEL_NAME);
        /// <summary>The GenApi schema version, "major.minor.subminor" ("" if absent).</summary>
        public string SchemaVersion => Text(NativeGenICamText.FLT_GENICAM_SCHEMA_VERSION);

        /// <summary>The features' names (value and command nodes) in document order.</summary>
        public IReadOnlyList<string> FeatureNames => names;

        /// <summary>Whether the description defines <paramref name="feature"/>.</summary>
        public bool Contains(string feature) => feature != null && names.Contains(feature);

        /// <summary>A feature's declaration.</summary>
        public unsafe FeatureInfo GetFeature(string feature)
        {
            int type;
            IntPtr kind, unit;
            FlatlineNative.flt_genicam_feature_info(LiveHandle, Feature(feature), &type, &kind, &unit);
            return new FeatureInfo(feature, (FeatureType)type, Utf8.Decode(kind), Utf8.Decode(unit));
        }

        /// <summary>The entries of a category of the feature tree, in the
        /// file's order: features and sub-categories (<see cref="GetFeature"/>
        /// tells them apart: <see cref="FeatureType.Category"/>). The tree
        /// starts at "Root". An entry may name a node the file lacks.
        /// <see cref="NotFoundException"/> for a name that is no category.</summary>
        public unsafe IReadOnlyList<string> GetCategory(string category = "Root")
        {
            var live = LiveHandle;
            if (category == null)
                throw new ArgumentNullException(nameof(category));
            var entries = new List<string>();
            while (true)
            {
                IntPtr name;
                try
                {
                    FlatlineNative.flt_genicam_category_entry(live, category, (ulong)entries.Count, &name);
                }
                catch (NotFoundException)
                {
                    // past the last entry, or no such category (an empty one
                    // is still a category)
                    if (entries.Count == 0 && !IsCategory(category))
                        throw;
                    return entries;
                }
                entries.Add(Utf8.Decode(name));
            }
        }

        private unsafe bool IsCategory(string name)
        {
            int type;
            IntPtr kind, unit;
            try
            {
                FlatlineNative.flt_genicam_feature_info(LiveHandle, name, &type, &kind, &unit);
            }
            catch (NotFoundException)
            {
                return false;
            }
            return type == (int)FeatureType.Category;
        }

        /// <summary>Puts <paramref name="data"/> (bytes in the device's memory
        /// order) at <paramref name="address"/> in the memory image.</summary>
        public unsafe void SetMemory(ulong address, byte[] data)
        {
            var live = LiveHandle;
            if (data == null)
                throw new ArgumentNullException(nameof(data));
            if (data.Length == 0)
                throw new ArgumentException("data is empty", nameof(data));
            fixed (byte* pd = data)
            {
                FlatlineNative.flt_genicam_set_memory(live, address, pd, (ulong)data.Length);
            }
        }

        /// <summary><paramref name="count"/> bytes of the memory image
        /// (<see cref="NotFoundException"/> for a byte it lacks).</summary>
        public unsafe byte[] GetMemory(ulong address, int count)
        {
            var live = LiveHandle;
            Shapes.AtLeast(count, 1, nameof(count));
            var data = new byte[count];
            fixed (byte* pd = data)
            {
                FlatlineNative.flt_genicam_get_memory(live, address, pd, (ulong)count);
            }
            return data;
        }

        /// <summary>Empties the memory image.</summary>
        public void ClearMemory() => FlatlineNative.flt_genicam_clear_memory(LiveHandle);

        /// <summary>The access mode for the current registers.</summary>
        public unsafe FeatureAccess GetAccess(string feature)
        {
            int access;
            FlatlineNative.flt_genicam_get_access(LiveHandle, Feature(feature), &access);
            return (FeatureAccess)access;
        }

        /// <summary>The feature's own pIsImplemented, pIsAvailable and pIsLocked.</summary>
        public unsafe (bool Implemented, bool Available, bool Locked) GetFlags(string feature)
        {
            int implemented, available, locked;
            FlatlineNative.flt_genicam_get_flags(LiveHandle, Feature(feature), &implemented, &available, &locked);
            return (implemented != 0, available != 0, locked != 0);
        }

        /// <summary>The register behind the feature (<see cref="NotFoundException"/>
        /// when its value is a formula of several nodes or a constant).</summary>
        public unsafe FeatureRegister GetRegister(string feature)
        {
            ulong address;
            uint length, lsb, msb;
            int bigEndian;
            FlatlineNative.flt_genicam_register(LiveHandle, Feature(feature), &address, &length, &lsb, &msb,
                                                &bigEndian);
            return new FeatureRegister(address, length, lsb, msb, bigEndian != 0);
        }

        /// <summary>The integer value (of an enumeration its entry's integer,
        /// of a boolean 0 or 1).</summary>
        public unsafe long GetInt(string feature)
        {
            long value;
            FlatlineNative.flt_genicam_get_int(LiveHandle, Feature(feature), &value);
            return value;
        }

        /// <summary>The value as a double.</summary>
        public double GetFloat(string feature)
        {
            FlatlineNative.flt_genicam_get_float(LiveHandle, Feature(feature), out double value);
            return value;
        }

        /// <summary>A string feature's value, or an enumeration's entry name.</summary>
        public unsafe string GetString(string feature)
        {
            IntPtr text;
            FlatlineNative.flt_genicam_get_string(LiveHandle, Feature(feature), &text);
            return Utf8.Decode(text);
        }

        /// <summary>An integer feature's bounds (long.MinValue / long.MaxValue / 1 without one).</summary>
        public unsafe (long Min, long Max, long Inc) GetIntBounds(string feature)
        {
            long min, max, inc;
            FlatlineNative.flt_genicam_int_bounds(LiveHandle, Feature(feature), &min, &max, &inc);
            return (min, max, inc);
        }

        /// <summary>A float feature's bounds (-/+ double.MaxValue without one).</summary>
        public unsafe (double Min, double Max) GetFloatBounds(string feature)
        {
            double min, max;
            FlatlineNative.flt_genicam_float_bounds(LiveHandle, Feature(feature), out min, out max);
            return (min, max);
        }

        /// <summary>An enumeration's entries, with their availability now.</summary>
        public unsafe IReadOnlyList<EnumEntryInfo> GetEntries(string feature)
        {
            var live = LiveHandle;
            FlatlineNative.flt_genicam_enum_count(live, Feature(feature), out UIntPtr count);
            var entries = new List<EnumEntryInfo>();
            for (ulong i = 0; i < count.ToUInt64(); ++i)
            {
                long value;
                int available;
                FlatlineNative.flt_genicam_enum_entry(live, feature, i, out IntPtr name, &value, &available);
                entries.Add(new EnumEntryInfo(Utf8.Decode(name), value, available != 0));
            }
            return entries;
        }

        /// <summary>Writes an integer, enumeration (by integer), boolean or float feature.</summary>
        public void SetInt(string feature, long value) =>
            FlatlineNative.flt_genicam_set_int(LiveHandle, Feature(feature), value);

        /// <summary>Writes a float feature (through its Converter formula if it has one).</summary>
        public void SetFloat(string feature, double value) =>
            FlatlineNative.flt_genicam_set_float(LiveHandle, Feature(feature), value);

        /// <summary>Writes a string feature, or an enumeration by entry name.</summary>
        public void SetString(string feature, string value)
        {
            if (value == null)
                throw new ArgumentNullException(nameof(value));
            FlatlineNative.flt_genicam_set_string(LiveHandle, Feature(feature), value);
        }

        /// <summary>Executes a command (writes its command value).</summary>
        public void Execute(string feature) => FlatlineNative.flt_genicam_execute(LiveHandle, Feature(feature));

        /// <summary>Frees the native description now. Further calls throw
        /// <see cref="ObjectDisposedException"/>; a second Dispose does nothing.</summary>
        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }

        public override string ToString() => $"{Vendor} {Model}: {names.Count} features";

        private unsafe string Text(NativeGenICamText which)
        {
            IntPtr text;
            FlatlineNative.flt_genicam_get_text(LiveHandle, (int)which, &text);
            return Utf8.Decode(text);
        }

        private GenICamHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(CameraDescription));
                return handle;
            }
        }

        private static string Feature(string feature) =>
            feature ?? throw new ArgumentNullException(nameof(feature));
    }
}
