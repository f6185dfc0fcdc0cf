// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.IO;

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
    /// What every exception libflatline throws for a failed C call carries:
    /// <see cref="Status"/>, the C status code, and <see cref="StatusName"/>.
    /// The exceptions themselves derive from the .NET exception of the same
    /// meaning (an invalid argument is an <see cref="ArgumentException"/>, a
    /// file that cannot be read an <see cref="IOException"/>), so code that
    /// catches those catches libflatline's too; code that wants every
    /// libflatline failure catches
    /// <c>catch (Exception e) when (e is IFlatlineException)</c>.
    /// </summary>
    public interface IFlatlineException
    {
        /// <summary>The C status code of the failed call.</summary>
        Status Status { get; }

        /// <summary>The C enumerator name, e.g. "FLT_ERR_INVALID_ARGUMENT".</summary>
        string StatusName { get; }
    }

    /// <summary>
    /// A libflatline call failed with a status no .NET exception means
    /// (FLT_ERR_INTERNAL, or a code newer than this binding).
    /// <see cref="Exception.Message"/> is the C library's message, which
    /// names the offending argument and its value. The handle that was used
    /// stays exactly as usable as before the call.
    /// </summary>
    public class FlatlineException : Exception, IFlatlineException
    {
        public FlatlineException(Status status, string? message)
            : base(Errors.MessageOf(status, message))
        {
            Status = status;
        }

        /// <inheritdoc/>
        public Status Status { get; }

        /// <inheritdoc/>
        public string StatusName => Errors.NameOf(Status);
    }

    /// <summary>FLT_ERR_INVALID_ARGUMENT: a value the C library rejected
    /// (for example fibers = 0, or positions that do not increase). An
    /// <see cref="ArgumentException"/>, like the wrong array sizes C# itself
    /// catches before the call (those have <see cref="ArgumentException.ParamName"/>
    /// set; this one names the argument in its message).</summary>
    public class InvalidArgumentException : ArgumentException, IFlatlineException
    {
        public InvalidArgumentException(Status status, string? message)
            : base(Errors.MessageOf(status, message)) { Status = status; }

        /// <inheritdoc/>
        public Status Status { get; }

        /// <inheritdoc/>
        public string StatusName => Errors.NameOf(Status);
    }

    /// <summary>FLT_ERR_OUT_OF_MEMORY: native memory could not be allocated,
    /// or a buffer was refused before allocating because it would pass the
    /// library's limits. An <see cref="OutOfMemoryException"/>, but not the
    /// runtime's: the managed heap is fine and the handle stays usable.</summary>
    public class FlatlineOutOfMemoryException : OutOfMemoryException, IFlatlineException
    {
        public FlatlineOutOfMemoryException(Status status, string? message)
            : base(Errors.MessageOf(status, message)) { Status = status; }

        /// <inheritdoc/>
        public Status Status { get; }

        /// <inheritdoc/>
        public string StatusName => Errors.NameOf(Status);
    }

    /// <summary>FLT_ERR_STATE: the call is not allowed in the object's current
    /// state (for example Pull before any Push, or EndSheet twice). An
    /// <see cref="InvalidOperationException"/>.</summary>
    public class FlatlineStateException : InvalidOperationException, IFlatlineException
    {
        public FlatlineStateException(Status status, string? message)
            : base(Errors.MessageOf(status, message)) { Status = status; }

        /// <inheritdoc/>
        public Status Status { get; }

        /// <inheritdoc/>
        public string StatusName => Errors.NameOf(Status);
    }

    /// <summary>FLT_ERR_BUFFER_FULL: a fixed-capacity buffer is full; pull
    /// finished rows, push smaller blocks, or raise RowCapacity. An
    /// <see cref="InvalidOperationException"/> (not in this state of the
    /// buffer).</summary>
    public class BufferFullException : InvalidOperationException, IFlatlineException
    {
        public BufferFullException(Status status, string? message)
            : base(Errors.MessageOf(status, message)) { Status = status; }

        /// <inheritdoc/>
        public Status Status { get; }

        /// <inheritdoc/>
        public string StatusName => Errors.NameOf(Status);
    }

    /// <summary>FLT_ERR_IO: a file could not be opened, read or written. An
    /// <see cref="IOException"/>; also the base of
    /// <see cref="FlatlineFormatException"/>.</summary>
    public class FlatlineIOException : IOException, IFlatlineException
    {
        public FlatlineIOException(Status status, string? message)
            : base(Errors.MessageOf(status, message)) { Status = status; }

        /// <inheritdoc/>
        public Status Status { get; }

        /// <inheritdoc/>
        public string StatusName => Errors.NameOf(Status);
    }

    /// <summary>FLT_ERR_FORMAT: a file or packet is malformed; the message
    /// names the field. A <see cref="FlatlineIOException"/>, so
    /// <c>catch (IOException)</c> around reading a file catches it.</summary>
    public class FlatlineFormatException : FlatlineIOException
    {
        public FlatlineFormatException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_DEVICE: a camera or transport failed. An
    /// <see cref="IOException"/> (the camera is an I/O device); also the base
    /// of <see cref="DeviceTimeoutException"/>.</summary>
    public class DeviceException : IOException, IFlatlineException
    {
        public DeviceException(Status status, string? message)
            : base(Errors.MessageOf(status, message)) { Status = status; }

        /// <inheritdoc/>
        public Status Status { get; }

        /// <inheritdoc/>
        public string StatusName => Errors.NameOf(Status);
    }

    /// <summary>FLT_ERR_TIMEOUT: a device did not answer in time. A
    /// <see cref="DeviceException"/>, so one catch covers a camera that
    /// fails and one that stops answering.</summary>
    public class DeviceTimeoutException : DeviceException
    {
        public DeviceTimeoutException(Status status, string? message) : base(status, message) { }
    }

    /// <summary>FLT_ERR_NOT_FOUND: something named (a device, a feature, an
    /// option) does not exist. A <see cref="KeyNotFoundException"/>.</summary>
    public class NotFoundException : KeyNotFoundException, IFlatlineException
    {
        public NotFoundException(Status status, string? message)
            : base(Errors.MessageOf(status, message)) { Status = status; }

        /// <inheritdoc/>
        public Status Status { get; }

        /// <inheritdoc/>
        public string StatusName => Errors.NameOf(Status);
    }

    /// <summary>FLT_ERR_NUMERIC: a singular system or a failed estimate. An
    /// <see cref="ArithmeticException"/>.</summary>
    public class NumericException : ArithmeticException, IFlatlineException
    {
        public NumericException(Status status, string? message)
            : base(Errors.MessageOf(status, message)) { Status = status; }

        /// <inheritdoc/>
        public Status Status { get; }

        /// <inheritdoc/>
        public string StatusName => Errors.NameOf(Status);
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

        /// <summary>The exception for a status: always an
        /// <see cref="IFlatlineException"/>.</summary>
        internal static Exception Create(Status status, string? message)
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

        internal static string NameOf(Status status) =>
            FlatlineNative.flt_status_string((int)status);

        // An empty C message still says what went wrong: the status's name.
        internal static string MessageOf(Status status, string? message) =>
            string.IsNullOrEmpty(message) ? NameOf(status) : message!;
    }
}
