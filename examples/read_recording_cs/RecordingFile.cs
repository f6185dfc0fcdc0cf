// SPDX-License-Identifier: Apache-2.0
using System;
using System.Collections.Generic;
using System.IO;
using System.IO.Compression;
using Microsoft.Data.Sqlite;

namespace FlatlineRecordingReader
{
    /// <summary>One block's rows of a libflatline recording.</summary>
    public sealed class RecordedBlock
    {
        public long FirstRow;
        public int Rows, Fibers;
        public double[] EncoderMm = Array.Empty<double>();
        public long[] TimeNs = Array.Empty<long>();
        /// <summary>[rows, fibers] 0 valid, 1 invalid input, 8 off the strip.</summary>
        public byte[,] Flags = new byte[0, 0];
        /// <summary>[rows, fibers] mm: (z_behind + z_ahead) / 2, NaN where Flags != 0.</summary>
        public double[,] Height = new double[0, 0];
        /// <summary>[rows, fibers] mm/mm: (z_ahead - z_behind) / laser spacing.</summary>
        public double[,] Slope = new double[0, 0];
    }

    /// <summary>
    /// Reads a libflatline recording (docs/record.md) without libflatline:
    /// SQLite through Microsoft.Data.Sqlite, the side data through .NET's
    /// ZLibStream, the heights' Rice codes here. Every block's CRC-32 is
    /// checked before it is decoded.
    /// </summary>
    public sealed class RecordingFile : IDisposable
    {
        private const uint BlockMagic = 0x42524C46;  // "FLRB"
        private const int RiceEscape = 48;
        private readonly SqliteConnection db;

        public RecordingFile(string path)
        {
            db = new SqliteConnection(new SqliteConnectionStringBuilder { DataSource = path }.ToString());
            db.Open();
            if (Scalar("PRAGMA application_id") != 0x464C5452)
                throw new InvalidDataException($"{path} is no flatline recording");
            long version = Scalar("PRAGMA user_version");
            if (version != 1)
                throw new InvalidDataException($"{path}: format version {version} (this reader knows 1)");
            using var cmd = db.CreateCommand();
            cmd.CommandText = "SELECT key, value FROM meta";
            using var r = cmd.ExecuteReader();
            while (r.Read())
                Meta[r.GetString(0)] = r.GetString(1);
            Fibers = int.Parse(Meta["fibers"], System.Globalization.CultureInfo.InvariantCulture);
            QuantumMm = double.Parse(Meta["quantum_mm"], System.Globalization.CultureInfo.InvariantCulture);
            LaserSpacingMm = double.Parse(Meta["laser_spacing_mm"], System.Globalization.CultureInfo.InvariantCulture);
        }

        public Dictionary<string, string> Meta { get; } = new Dictionary<string, string>();
        public int Fibers { get; }
        public double QuantumMm { get; }
        public double LaserSpacingMm { get; }

        private long Scalar(string sql)
        {
            using var cmd = db.CreateCommand();
            cmd.CommandText = sql;
            return Convert.ToInt64(cmd.ExecuteScalar(), System.Globalization.CultureInfo.InvariantCulture);
        }

        /// <summary>The blocks in row order.</summary>
        public IEnumerable<RecordedBlock> Blocks()
        {
            using var cmd = db.CreateCommand();
            cmd.CommandText = "SELECT block, first_row, codec, crc32, payload FROM blocks ORDER BY first_row";
            using var r = cmd.ExecuteReader();
            while (r.Read())
            {
                long block = r.GetInt64(0);
                if (r.GetInt64(2) != 1)
                    throw new InvalidDataException($"block {block}: unknown codec");
                var payload = (byte[])r.GetValue(4);
                if (Crc32(payload) != (uint)r.GetInt64(3))
                    throw new InvalidDataException($"block {block}: its CRC-32 does not match");
                yield return Decode(payload, r.GetInt64(1));
            }
        }

        private RecordedBlock Decode(byte[] p, long firstRow)
        {
            if (BitConverter.ToUInt32(p, 0) != BlockMagic)
                throw new InvalidDataException("no block magic");
            int rows = (int)BitConverter.ToUInt32(p, 4), fibers = (int)BitConverter.ToUInt32(p, 8);
            if (fibers != Fibers || BitConverter.ToDouble(p, 12) != QuantumMm)
                throw new InvalidDataException("not a block of this recording");
            int sideBytes = (int)BitConverter.ToUInt32(p, 20), deflated = (int)BitConverter.ToUInt32(p, 24);
            var side = new byte[sideBytes];
            using (var z = new ZLibStream(new MemoryStream(p, 28, deflated), CompressionMode.Decompress))
            {
                int got = 0;
                while (got < sideBytes)
                {
                    int n = z.Read(side, got, sideBytes - got);
                    if (n == 0)
                        throw new InvalidDataException("side data short");
                    got += n;
                }
            }
            int at = 28 + deflated;
            var b = new RecordedBlock { FirstRow = firstRow, Rows = rows, Fibers = fibers };
            b.EncoderMm = new double[rows];
            b.TimeNs = new long[rows];
            Buffer.BlockCopy(side, 0, b.EncoderMm, 0, rows * 8);
            Buffer.BlockCopy(side, rows * 8, b.TimeNs, 0, rows * 8);
            // Then left, right (f64), six u32 counters, row flags, strip flags.
            int states = rows * (8 * 4 + 4 * 6 + 2);
            b.Flags = new byte[rows, fibers];
            for (int i = 0; i < rows * fibers; ++i)
                b.Flags[i / fibers, i % fibers] = (byte)(side[states + i] & 0x0F);
            var z2 = new double[2][];
            for (int laser = 0; laser < 2; ++laser)
            {
                int k = p[at];
                int n = (int)BitConverter.ToUInt32(p, at + 1), ub = (int)BitConverter.ToUInt32(p, at + 5);
                int bb = (int)BitConverter.ToUInt32(p, at + 9), ne = (int)BitConverter.ToUInt32(p, at + 13);
                at += 17;
                int unary = at, binary = at + ub, escapes = at + ub + bb;
                at = escapes + 8 * ne;
                long ubit = 0, bbit = 0, previous = 0;
                int esc = 0, j = 0;
                var z = new double[rows * fibers];
                for (int i = 0; i < rows * fibers; ++i)
                {
                    if (b.Flags[i / fibers, i % fibers] != 0)
                    {
                        z[i] = double.NaN;
                        continue;
                    }
                    // Unary: zeros ended by a one; binary: k bits; LSB first.
                    long q = 0;
                    while (((p[unary + (ubit >> 3)] >> (int)(ubit & 7)) & 1) == 0)
                    {
                        ++q;
                        ++ubit;
                    }
                    ++ubit;
                    ulong rem = 0;
                    for (int bit = 0; bit < k; ++bit, ++bbit)
                        rem |= (ulong)((p[binary + (bbit >> 3)] >> (int)(bbit & 7)) & 1) << bit;
                    ulong u = q == RiceEscape ? BitConverter.ToUInt64(p, escapes + 8 * esc++)
                                              : ((ulong)q << k) | rem;
                    previous += (long)(u >> 1) ^ -(long)(u & 1);
                    z[i] = previous * QuantumMm;
                    ++j;
                }
                if (j != n)
                    throw new InvalidDataException("height count differs from the valid samples");
                z2[laser] = z;
            }
            b.Height = new double[rows, fibers];
            b.Slope = new double[rows, fibers];
            for (int i = 0; i < rows * fibers; ++i)
            {
                double zb = z2[0][i], za = z2[1][i];
                b.Height[i / fibers, i % fibers] = (zb + za) * 0.5;
                b.Slope[i / fibers, i % fibers] = (za - zb) / LaserSpacingMm;
            }
            return b;
        }

        private static readonly uint[] Table = MakeTable();

        private static uint[] MakeTable()
        {
            var t = new uint[256];
            for (uint i = 0; i < 256; ++i)
            {
                uint c = i;
                for (int k = 0; k < 8; ++k)
                    c = (c & 1) != 0 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
                t[i] = c;
            }
            return t;
        }

        /// <summary>CRC-32 (ISO-HDLC, zlib's crc32).</summary>
        public static uint Crc32(byte[] data)
        {
            uint c = 0xFFFFFFFFu;
            foreach (byte x in data)
                c = Table[(c ^ x) & 0xFF] ^ (c >> 8);
            return c ^ 0xFFFFFFFFu;
        }

        public void Dispose() => db.Dispose();
    }
}
