// SPDX-License-Identifier: Apache-2.0
using System;
using System.IO;
using System.Reflection;
using System.Runtime.InteropServices;

namespace Flatline
{
    /// <summary>
    /// Finds the native glue library "flatline_csharp" (which links
    /// libflatline). By default .NET probes for it as for any DllImport:
    /// libflatline_csharp.so on Linux, flatline_csharp.dll on Windows,
    /// libflatline_csharp.dylib on macOS, in the application folder and in
    /// runtimes/&lt;rid&gt;/native of the NuGet package. An integrator can
    /// instead name a folder or a file with <see cref="Library.NativeLibraryPath"/>
    /// or the environment variable FLATLINE_NATIVE_PATH (the property wins).
    /// </summary>
    internal static class NativeLoader
    {
        internal const string GlueName = "flatline_csharp";
        /// <summary>The testing tier's glue (Flatline.Testing), found beside the main one.</summary>
        internal const string TestingGlueName = "flatline_testing_csharp";
        internal const string EnvironmentVariable = "FLATLINE_NATIVE_PATH";

        private static readonly object Gate = new object();
        private static string? configuredPath;
        private static bool bound;

        internal static string? ConfiguredPath
        {
            get { lock (Gate) return configuredPath; }
            set
            {
                lock (Gate)
                {
                    if (bound)
                        throw new InvalidOperationException(
                            "Library.NativeLibraryPath must be set before the first call into " +
                            "libflatline: the native library is already loaded");
                    configuredPath = value;
                }
            }
        }

        /// <summary>The platform's file name of a native library, as .NET probes it.</summary>
        internal static string PlatformFileName(string name)
        {
            if (RuntimeInformation.IsOSPlatform(OSPlatform.Windows))
                return name + ".dll";
            if (RuntimeInformation.IsOSPlatform(OSPlatform.OSX))
                return "lib" + name + ".dylib";
            return "lib" + name + ".so";
        }

        /// <summary>The glue file an override names: a folder (the glue is
        /// looked up inside it by its platform name) or the file itself.
        /// null when no override is set.</summary>
        internal static string? ResolveOverride(string? configured)
        {
            if (string.IsNullOrEmpty(configured))
                return null;
            string full = Path.GetFullPath(configured);
            return Directory.Exists(full) ? Path.Combine(full, PlatformFileName(GlueName)) : full;
        }

        private static string? EffectiveOverride()
        {
            string? path = ConfiguredPath;
            if (string.IsNullOrEmpty(path))
                path = Environment.GetEnvironmentVariable(EnvironmentVariable);
            return ResolveOverride(path);
        }

        /// <summary>The core library's file name on Windows: libflatline.dll,
        /// never flatline.dll, which on a case-insensitive file system is this
        /// managed assembly, Flatline.dll.</summary>
        internal const string WindowsCoreFile = "libflatline.dll";

        /// <summary>On Windows, a DLL loaded by full path does not find its
        /// own dependencies beside it; load libflatline.dll from the same
        /// folder first. (On Linux the glue carries RPATH $ORIGIN.)</summary>
        private static void PreloadCore(string glueFile, Func<string, bool> tryLoad)
        {
            if (!RuntimeInformation.IsOSPlatform(OSPlatform.Windows))
                return;
            string core = Path.Combine(Path.GetDirectoryName(glueFile) ?? ".", WindowsCoreFile);
            if (File.Exists(core))
                tryLoad(core);
        }

#if NETCOREAPP3_0_OR_GREATER
#pragma warning disable CA2255 // a library may use a module initializer for this
        [System.Runtime.CompilerServices.ModuleInitializer]
        internal static void Register()
        {
            NativeLibrary.SetDllImportResolver(typeof(NativeLoader).Assembly, Resolve);
        }
#pragma warning restore CA2255

        private static IntPtr Resolve(string libraryName, Assembly assembly, DllImportSearchPath? searchPath)
        {
            if (libraryName != GlueName && libraryName != TestingGlueName)
                return IntPtr.Zero;
            lock (Gate)
                bound = true;
            string? file = EffectiveOverride();
            if (file == null)
                return IntPtr.Zero;  // the default probing
            if (libraryName == TestingGlueName)
                file = Path.Combine(Path.GetDirectoryName(file) ?? ".", PlatformFileName(TestingGlueName));
            if (!File.Exists(file))
                throw new DllNotFoundException(
                    $"libflatline's C# glue was not found at '{file}' (from Library.NativeLibraryPath " +
                    $"or {EnvironmentVariable})");
            PreloadCore(file, core => NativeLibrary.TryLoad(core, out _));
            return NativeLibrary.Load(file);
        }

        /// <summary>Nothing to do: the resolver is registered when the
        /// assembly loads.</summary>
        internal static void EnsureLoaded() { }

        /// <summary>Nothing to do: the resolver finds the testing glue too.</summary>
        internal static void EnsureTestingLoaded() { }
#else
        // netstandard2.0 has no NativeLibrary: load the override by full path
        // before the first P/Invoke; the loader then binds DllImport
        // "flatline_csharp" to the module already in the process (Windows
        // matches loaded modules by name).
        [DllImport("kernel32", CharSet = CharSet.Unicode, SetLastError = true)]
        private static extern IntPtr LoadLibraryW(string path);

        private static bool preloaded;

        internal static void EnsureLoaded()
        {
            lock (Gate)
            {
                if (preloaded)
                    return;
                preloaded = true;
                bound = true;
            }
            string? file = EffectiveOverride();
            if (file == null || !RuntimeInformation.IsOSPlatform(OSPlatform.Windows))
                return;
            if (!File.Exists(file))
                throw new DllNotFoundException(
                    $"libflatline's C# glue was not found at '{file}' (from Library.NativeLibraryPath " +
                    $"or {EnvironmentVariable})");
            PreloadCore(file, core => LoadLibraryW(core) != IntPtr.Zero);
            if (LoadLibraryW(file) == IntPtr.Zero)
                throw new DllNotFoundException($"could not load '{file}' (error {Marshal.GetLastWin32Error()})");
        }

        private static bool testingPreloaded;

        /// <summary>The testing tier's glue from the override's folder
        /// (Windows), before the first call into Flatline.Testing.</summary>
        internal static void EnsureTestingLoaded()
        {
            EnsureLoaded();
            lock (Gate)
            {
                if (testingPreloaded)
                    return;
                testingPreloaded = true;
            }
            string? file = EffectiveOverride();
            if (file == null || !RuntimeInformation.IsOSPlatform(OSPlatform.Windows))
                return;
            string dir = Path.GetDirectoryName(file) ?? ".";
            string testing = Path.Combine(dir, PlatformFileName(TestingGlueName));
            if (File.Exists(testing))
            {
                // its own dependency, libflatline_testing, beside it
                foreach (string library in Directory.GetFiles(dir, "*flatline_testing.dll"))
                    LoadLibraryW(library);
                if (LoadLibraryW(testing) == IntPtr.Zero)
                    throw new DllNotFoundException(
                        $"could not load '{testing}' (error {Marshal.GetLastWin32Error()})");
            }
        }
#endif
    }
}
