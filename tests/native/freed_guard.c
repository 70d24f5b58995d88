/* Test helper, loaded with LD_PRELOAD: C++ objects deleted in the process are not freed but filled
 * with a pattern and kept; when the process ends, after every exit handler and every library's
 * destructor functions, every kept block must still hold the pattern. A block that does not was
 * written after it was deleted: the helper says so on stderr and exits with status 99. Otherwise
 * it says how many objects it checked. (tests/test_fmu.py: the exit of processes that ran FMUs.)
 *
 *   gcc -shared -fPIC -O2 -o freed_guard.so freed_guard.c */
#include <malloc.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define PATTERN 0xA5
#define MAX_BLOCKS (1u << 21)

static void *blocks[MAX_BLOCKS];
static size_t sizes[MAX_BLOCKS];
static size_t kept;
static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;

static void keep(void *p)
{
    size_t n;
    if (p == NULL)
        return;
    n = malloc_usable_size(p);
    pthread_mutex_lock(&lock);
    if (kept < MAX_BLOCKS) {
        memset(p, PATTERN, n);
        blocks[kept] = p;
        sizes[kept] = n;
        kept++;
        p = NULL;
    }
    pthread_mutex_unlock(&lock);
    free(p); /* beyond MAX_BLOCKS: freed as usual */
}

/* operator delete and delete[], plain, sized, aligned and sized aligned (Itanium C++ ABI names). */
void _ZdlPv(void *p) { keep(p); }
void _ZdaPv(void *p) { keep(p); }
void _ZdlPvm(void *p, size_t n) { (void)n; keep(p); }
void _ZdaPvm(void *p, size_t n) { (void)n; keep(p); }
void _ZdlPvSt11align_val_t(void *p, size_t a) { (void)a; keep(p); }
void _ZdaPvSt11align_val_t(void *p, size_t a) { (void)a; keep(p); }
void _ZdlPvmSt11align_val_t(void *p, size_t n, size_t a) { (void)n; (void)a; keep(p); }
void _ZdaPvmSt11align_val_t(void *p, size_t n, size_t a) { (void)n; (void)a; keep(p); }

static void check(void *unused)
{
    (void)unused;
    size_t i, j;
    for (i = 0; i < kept; i++) {
        const unsigned char *b = blocks[i];
        for (j = 0; j < sizes[i]; j++) {
            if (b[j] != PATTERN) {
                fprintf(stderr, "freed_guard: a C++ object of %zu bytes was written at offset %zu "
                        "after it was deleted\n", sizes[i], j);
                fflush(stderr);
                _exit(99);
            }
        }
    }
    fprintf(stderr, "freed_guard: %zu deleted objects, none written after\n", kept);
}

extern int __cxa_atexit(void (*function)(void *), void *argument, void *dso_handle);

/* Registered before the dynamic linker registers its own exit-time work (_dl_fini, which runs the
 * libraries' destructor functions), so the check runs after it, last of all. */
__attribute__((constructor)) static void arm(void)
{
    __cxa_atexit(check, NULL, NULL);
}
