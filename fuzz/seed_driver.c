/*
 * seed_driver.c - a main for a libFuzzer harness built without libFuzzer: runs each file named on
 * the command line (or each file of a directory named there, not recursively) once through
 * LLVMFuzzerTestOneInput.
 *
 * `make check` builds each harness with it, in the suite's own build (plain, or ASan + UBSan for
 * check-asan), and runs the seed corpus, so that a harness that no longer compiles, or a seed that
 * breaks the parser's contract, fails the suite without a fuzzing run. The harness aborts on a
 * broken contract; this driver exits 1 on a file it cannot read, and prints the count of inputs
 * run on standard error.
 */
#include <dirent.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* runs one file; 0, or -1 when it cannot be read */
static int run_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) return -1;
    size_t cap = 1 << 12, n = 0;
    uint8_t *buf = malloc(cap);
    for (;;) {
        if (buf == NULL) break;
        n += fread(buf + n, 1, cap - n, f);
        if (n < cap) break;
        uint8_t *bigger = realloc(buf, 2 * cap);
        if (bigger == NULL) {
            free(buf);
            buf = NULL;
            break;
        }
        buf = bigger;
        cap *= 2;
    }
    int bad = ferror(f) || buf == NULL;
    fclose(f);
    /* libFuzzer hands over a buffer of exactly the input's size: so does this, from the heap,
       so that ASan sees a read past its end */
    uint8_t *exact = bad ? NULL : malloc(n > 0 ? n : 1);
    if (exact != NULL) {
        memcpy(exact, buf, n);
        LLVMFuzzerTestOneInput(exact, n);
    }
    free(exact);
    free(buf);
    return bad || exact == NULL ? -1 : 0;
}

int main(int argc, char **argv)
{
    int runs = 0;
    for (int a = 1; a < argc; a++) {
        struct stat st;
        if (stat(argv[a], &st) != 0) {
            fprintf(stderr, "%s: cannot read %s\n", argv[0], argv[a]);
            return 1;
        }
        if (!S_ISDIR(st.st_mode)) {
            if (run_file(argv[a]) != 0) {
                fprintf(stderr, "%s: cannot read %s\n", argv[0], argv[a]);
                return 1;
            }
            runs++;
            continue;
        }
        DIR *dir = opendir(argv[a]);
        if (dir == NULL) {
            fprintf(stderr, "%s: cannot read %s\n", argv[0], argv[a]);
            return 1;
        }
        for (struct dirent *e; (e = readdir(dir)) != NULL;) {
            if (e->d_name[0] == '.') continue;
            char path[4096];
            snprintf(path, sizeof path, "%s/%s", argv[a], e->d_name);
            if (stat(path, &st) != 0 || !S_ISREG(st.st_mode)) continue;
            if (run_file(path) != 0) {
                fprintf(stderr, "%s: cannot read %s\n", argv[0], path);
                closedir(dir);
                return 1;
            }
            runs++;
        }
        closedir(dir);
    }
    fprintf(stderr, "%s: %d inputs run\n", argv[0], runs);
    return 0;
}
