using System;
using System.Collections.Generic;

namespace Flatline
{
    /// <summary>One option key of the C library: its name, inclusive bounds,
    /// default, and whether it takes whole numbers only.</summary>
    public sealed class OptionInfo
    {
        internal OptionInfo(string name, double min, double max, double defaultValue, bool isInteger)
        {
            Name = name;
            Min = min;
            Max = max;
            Default = defaultValue;
            IsInteger = isInteger;
        }

        public string Name { get; }
        public double Min { get; }
        public double Max { get; }
        public double Default { get; }
        public bool IsInteger { get; }
        public override string ToString() => $"{Name} [{Min}, {Max}] default {Default}{(IsInteger ? " (integer)" : "")}";
    }

    /// <summary>
    /// A bag of option values (flt_options). Keys are set by their C name
    /// ("knot_spacing", ...) through flt_option_find, so an option added to
    /// the C library is usable here without a binding change; the typed
    /// properties cover the options known when this binding was written.
    /// Keys never set keep their default. Objects created from a bag keep
    /// their own copy of the values, so the bag may be disposed right after.
    /// </summary>
    public sealed class FlatlineOptions : IDisposable
    {
        private readonly OptionsHandle handle;

        static FlatlineOptions() => NativeLoader.EnsureLoaded();

        /// <summary>A bag holding every default.</summary>
        public FlatlineOptions()
        {
            FlatlineNative.flt_options_create(out handle);
            handle.Track(0);
        }

        /// <summary>Every option key the native library knows, in its order.</summary>
        public static IReadOnlyList<OptionInfo> Available
        {
            get
            {
                NativeLoader.EnsureLoaded();
                var keys = new List<OptionInfo>();
                for (ulong index = 0; ; ++index)
                {
                    int key;
                    try
                    {
                        FlatlineNative.flt_option_at(index, out key);
                    }
                    catch (NotFoundException)
                    {
                        break;  // past the last key
                    }
                    keys.Add(Info(key));
                }
                return keys;
            }
        }

        /// <summary>Describes one option by name; <see cref="NotFoundException"/>
        /// if the library has no such option.</summary>
        public static OptionInfo Describe(string name) => Info(Key(name));

        /// <summary>The value of an option by its C name.</summary>
        public double this[string name]
        {
            get => Get(name);
            set => Set(name, value);
        }

        /// <summary>Sets an option by its C name. <see cref="NotFoundException"/>
        /// for an unknown name; <see cref="InvalidArgumentException"/> for a
        /// NaN, a value outside the bounds or a fraction for an integer option
        /// (the bag is then unchanged).</summary>
        public FlatlineOptions Set(string name, double value)
        {
            int key = Key(name);
            FlatlineNative.flt_options_set(LiveHandle, key, value);
            return this;
        }

        /// <summary>Reads an option by its C name (its default if never set).</summary>
        public double Get(string name)
        {
            int key = Key(name);
            FlatlineNative.flt_options_get(LiveHandle, key, out double value);
            return value;
        }

        /// <summary>Distance L between spline knots along travel, mm; 0 means
        /// "equal to LaserSpacing".</summary>
        public double KnotSpacing { get => Get("knot_spacing"); set => Set("knot_spacing", value); }
        /// <summary>Distance between the two laser lines along travel, mm.</summary>
        public double LaserSpacing { get => Get("laser_spacing"); set => Set("laser_spacing", value); }
        /// <summary>Standard deviation of one measured height, mm.</summary>
        public double HeightSigma { get => Get("height_sigma"); set => Set("height_sigma", value); }
        /// <summary>Standard deviation of one measured slope, mm/mm.</summary>
        public double SlopeSigma { get => Get("slope_sigma"); set => Set("slope_sigma", value); }
        /// <summary>Weight of the smoothness prior relative to one height sample.</summary>
        public double CurvatureWeight { get => Get("curvature_weight"); set => Set("curvature_weight", value); }
        /// <summary>Weight of the prior against jumps of the curvature at the
        /// knots, relative to one height sample: it removes the wiggle the
        /// secant slopes cannot see.</summary>
        public double CurvatureJumpWeight { get => Get("curvature_jump_weight"); set => Set("curvature_jump_weight", value); }
        /// <summary>Knots beyond a knot that must be complete before the
        /// streaming reconstructor emits it.</summary>
        public int LagKnots { get => (int)Get("lag_knots"); set => Set("lag_knots", value); }
        /// <summary>Runs of invalid samples whose valid neighbours are further
        /// apart than this are flagged Gap, mm.</summary>
        public double MaxGap { get => Get("max_gap"); set => Set("max_gap", value); }
        /// <summary>Rows the streaming reconstructor can hold (9 bytes per
        /// row and fiber).</summary>
        public int RowCapacity { get => (int)Get("row_capacity"); set => Set("row_capacity", value); }
        /// <summary>Model the vibration as a rigid heave and roll of each
        /// frame (one line across the strip) and take it out of the fibers'
        /// shape; see the C header for the trade-offs.</summary>
        public bool RigidMotion { get => Get("rigid_motion") != 0; set => Set("rigid_motion", value ? 1 : 0); }
        /// <summary>With RigidMotion, standard deviation of a height's
        /// deviation from its frame's line across the strip, mm.</summary>
        public double ShapeSigma { get => Get("shape_sigma"); set => Set("shape_sigma", value); }

        public void Dispose()
        {
            handle.Dispose();
            GC.SuppressFinalize(this);
        }

        internal OptionsHandle LiveHandle
        {
            get
            {
                if (handle.IsClosed)
                    throw new ObjectDisposedException(nameof(FlatlineOptions));
                return handle;
            }
        }

        internal static int Key(string name)
        {
            if (name == null)
                throw new ArgumentNullException(nameof(name));
            FlatlineNative.flt_option_find(name, out int key);
            return key;
        }

        private static OptionInfo Info(int key)
        {
            FlatlineNative.flt_option_info(key, out IntPtr name, out double min, out double max,
                                           out double defaultValue, out int isInteger);
            return new OptionInfo(Utf8.Decode(name), min, max, defaultValue, isInteger != 0);
        }

        /// <summary>The caller's bag, or a bag of defaults for null (the
        /// marshaller cannot pass a null SafeHandle), disposed with the scope.</summary>
        internal static Scope Borrow(FlatlineOptions options) =>
            options != null ? new Scope(options.LiveHandle, null) : new Scope(null, new FlatlineOptions());

        internal readonly struct Scope : IDisposable
        {
            private readonly OptionsHandle borrowed;
            private readonly FlatlineOptions owned;
            internal Scope(OptionsHandle borrowed, FlatlineOptions owned)
            {
                this.borrowed = borrowed;
                this.owned = owned;
            }
            internal OptionsHandle Handle => borrowed ?? owned.handle;
            public void Dispose() => owned?.Dispose();
        }
    }
}
