// SPDX-License-Identifier: Apache-2.0
/* Runs a libFuzzer harness over files, without libFuzzer: the ctest test
 * fuzz.<harness> replays the committed seed corpus and the regression
 * inputs of crashes found (tests/fuzz/regressions/<harness>/) in every
 * build, the ASan + UBSan one included.
 *   usage: replay_<harness> FILE_OR_DIRECTORY...  */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int run_file(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "cannot open %s\n", path);
        return 1;
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *data = malloc(n > 0 ? (size_t)n : 1);
    size_t got = n > 0 ? fread(data, 1, (size_t)n, f) : 0;
    fclose(f);
    if ((long)got != n) {
        fprintf(stderr, "cannot read %s\n", path);
        free(data);
        return 1;
    }
    LLVMFuzzerTestOneInput(data, got); /* a failure aborts */
    free(data);
    return 0;
}

int main(int argc, char **argv) {
    int files = 0, errors = 0;
    for (int i = 1; i < argc; ++i) {
        struct stat st;
        if (stat(argv[i], &st) != 0)
            continue; /* an absent folder: nothing to replay */
        if (!S_ISDIR(st.st_mode)) {
            errors += run_file(argv[i]);
            ++files;
            continue;
        }
        DIR *d = opendir(argv[i]);
        struct dirent *e;
        while (d && (e = readdir(d)) != NULL) {
            if (e->d_name[0] == '.')
                continue;
            char path[4096];
            snprintf(path, sizeof path, "%s/%s", argv[i], e->d_name);
            errors += run_file(path);
            ++files;
        }
        if (d)
            closedir(d);
    }
    printf("replayed %d inputs without a crash\n", files);
    return errors ? 1 : (files ? 0 : 1);
}
