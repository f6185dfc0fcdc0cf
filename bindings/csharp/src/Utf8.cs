// SPDX-License-Identifier: Apache-2.0
using System;
using System.Runtime.InteropServices;
using System.Text;

namespace Flatline
{
    /// <summary>UTF-8 strings across the boundary, on every platform (the
    /// default LPStr marshalling is the ANSI code page on Windows).</summary>
    internal static class Utf8
    {
        /// <summary>A NUL-terminated UTF-8 copy of <paramref name="text"/>, or
        /// null for null (the C side sees NULL).</summary>
        internal static byte[]? Encode(string? text)
        {
            if (text == null)
                return null;
            if (text.IndexOf('\0') >= 0)
                throw new ArgumentException("the string contains a NUL character", nameof(text));
            int length = Encoding.UTF8.GetByteCount(text);
            var bytes = new byte[length + 1];
            Encoding.UTF8.GetBytes(text, 0, text.Length, bytes, 0);
            return bytes;
        }

        /// <summary>Reads a NUL-terminated UTF-8 string the library owns.
        /// The C functions hand out a string whenever they return FLT_OK
        /// (a failure has thrown before this is called); a NULL all the
        /// same reads as "", so the managed string is never null.</summary>
        internal static unsafe string Decode(IntPtr text)
        {
            if (text == IntPtr.Zero)
                return "";
            byte* p = (byte*)text;
            int length = 0;
            while (p[length] != 0)
                ++length;
            return Encoding.UTF8.GetString(p, length);
        }
    }
}
