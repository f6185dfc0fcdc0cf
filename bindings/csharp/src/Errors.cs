// SPDX-License-Identifier: Apache-2.0
using System;

namespace Flatline
{
    /// <summary>
    /// The status codes of the C API (flt_status in flatline/common.h).
    /// Codes are stable; new ones are only ever added.
    /// </summary>
    public enum Status
    {
        Ok = 0,
        InvalidArgument = -1,
        OutOfMemory = -2,
        State = -3,
        BufferFull = -4,
        IO = -5,
        Format = -6,
        Device = -7,
        Timeout = -8,
        NotFound = -9,
        Numeric = -10,
        Internal = -99,
    }

    /// <summary>
    /// A libflatline call failed. <see cref="Status"/> is the C status code and
    /// <see cref="Exception.Message"/> the C library's message, which names the
    /// offending argument and its value. The handle that was used stays exactly
    /// as usable as before the call. Subclasses exist where a caller would
    /// catch them separately.
    /// </summary>
    public class FlatlineException : Exception
    {
        public FlatlineException(Status status, string? message)
            : base(string.IsNullOrEmpty(message) ? NameOf(status) : message)
        {
            Status = status;
        }

        /// <summary>The C status code of the failed call.</summary>
        public Status Status { get; }

        /// <summary>The C enumerator name, e.g. "FLT_ERR_INVALID_ARGUMENT".</summary>
        public string StatusName => NameOf(Status);

        private static string NameOf(Status status) =>
            FlatlineNative.flt_status_string((int)status);
    }

    /// <summary>FLT_ERR_INVALID_ARGUMENT: a value the C library rejected
    /// (for example fibers = 0, or positions that do not increase). Wrong
    /// array sizes are caught earlier, in C#, as <see cref="ArgumentException"/>.</summary>
    public class InvalidArgumentException : FlatlineException
    {
        public InvalidArgumentException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_OUT_OF_MEMORY: native memory could not be allocated.</summary>
    public class FlatlineOutOfMemoryException : FlatlineException
    {
        public FlatlineOutOfMemoryException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_STATE: the call is not allowed in the object's current
    /// state (for example Pull before any Push, or EndSheet twice).</summary>
    public class FlatlineStateException : FlatlineException
    {
        public FlatlineStateException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_BUFFER_FULL: a fixed-capacity buffer is full; pull
    /// finished rows, push smaller blocks, or raise RowCapacity.</summary>
    public class BufferFullException : FlatlineException
    {
        public BufferFullException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_IO: a file could not be opened, read or written.
    /// Also the base of <see cref="FlatlineFormatException"/>.</summary>
    public class FlatlineIOException : FlatlineException
    {
        public FlatlineIOException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_FORMAT: a file or packet is malformed; the message
    /// names the field.</summary>
    public class FlatlineFormatException : FlatlineIOException
    {
        public FlatlineFormatException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_DEVICE: a camera or transport failed. Also the base of
    /// <see cref="DeviceTimeoutException"/>.</summary>
    public class DeviceException : FlatlineException
    {
        public DeviceException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_TIMEOUT: a device did not answer in time.</summary>
    public class DeviceTimeoutException : DeviceException
    {
        public DeviceTimeoutException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_NOT_FOUND: something named (a device, a feature, an
    /// option) does not exist.</summary>
    public class NotFoundException : FlatlineException
    {
        public NotFoundException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_NUMERIC: a singular system or a failed estimate.</summary>
    public class NumericException : FlatlineException
    {
        public NumericException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_INTERNAL: a bug in libflatline; please report it with
    /// the message.</summary>
    public class FlatlineInternalException : FlatlineException
    {
        public FlatlineInternalException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>The one place where a C status becomes an exception. The
    /// generated layer calls <see cref="Check"/> after every function that
    /// returns flt_status (see swig/common.i).</summary>
    internal static class Errors
    {
        internal static void Check(int status)
        {
            if (status == 0)
                return;
            // The message is thread-local in the library and P/Invoke runs on
            // this thread, so it belongs to the call that just failed.
            throw Create((Status)status, FlatlineNative.flt_last_error_message());
        }

        internal static FlatlineException Create(Status status, string? message)
        {
            switch (status)
            {
                case Status.InvalidArgument: return new InvalidArgumentException(status, message);
                case Status.OutOfMemory: return new FlatlineOutOfMemoryException(status, message);
                case Status.State: return new FlatlineStateException(status, message);
                case Status.BufferFull: return new BufferFullException(status, message);
                case Status.IO: return new FlatlineIOException(status, message);
                case Status.Format: return new FlatlineFormatException(status, message);
                case Status.Device: return new DeviceException(status, message);
                case Status.Timeout: return new DeviceTimeoutException(status, message);
                case Status.NotFound: return new NotFoundException(status, message);
                case Status.Numeric: return new NumericException(status, message);
                case Status.Internal: return new FlatlineInternalException(status, message);
                default: return new FlatlineException(status, message);
            }
        }
    }
}
