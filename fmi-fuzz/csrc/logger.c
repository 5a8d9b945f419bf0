/*
 * The fmi2CallbackLogger the fuzzer hands to the FMU under test.
 *
 * fmi2CallbackLogger is C-variadic and printf-style; Rust can call such a function but cannot
 * define one. This shim formats the message with vsnprintf and hands it to the Rust function
 * stored at the start of the componentEnvironment (struct fmi_fuzz_log_header), together with
 * the raw instance-name and category pointers so the Rust side can check them for NULL.
 *
 * A NULL componentEnvironment (the fuzzer passes one on purpose in some fmi2Instantiate calls)
 * cannot be routed: such messages are only counted (fmi_fuzz_orphan_messages).
 * A NULL format is delivered as a NULL message, so the Rust side can report it.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

typedef void (*fmi_fuzz_deliver_fn)(void *env, const char *instance, int status,
                                    const char *category, const char *message, size_t len);

/* Must match the first field of `LogSink` in src/log.rs. */
struct fmi_fuzz_log_header {
    fmi_fuzz_deliver_fn deliver;
};

static long orphans;

long fmi_fuzz_orphan_messages(void) { return __atomic_load_n(&orphans, __ATOMIC_SEQ_CST); }

void fmi_fuzz_logger(void *env, const char *instance, int status, const char *category,
                     const char *fmt, ...) {
    const struct fmi_fuzz_log_header *h = (const struct fmi_fuzz_log_header *)env;
    if (h == NULL || h->deliver == NULL) {
        __atomic_fetch_add(&orphans, 1, __ATOMIC_SEQ_CST);
        return;
    }
    if (fmt == NULL) {
        h->deliver(env, instance, status, category, NULL, 0);
        return;
    }
    char stack[1024];
    char *heap = NULL;
    const char *text = stack;
    va_list ap;
    va_list again;
    va_start(ap, fmt);
    va_copy(again, ap);
    int n = vsnprintf(stack, sizeof stack, fmt, ap);
    va_end(ap);
    size_t len;
    if (n < 0) {
        text = fmt;
        len = 0;
        while (fmt[len] != '\0') {
            len++;
        }
    } else if ((size_t)n < sizeof stack) {
        len = (size_t)n;
    } else {
        heap = (char *)malloc((size_t)n + 1);
        if (heap != NULL && vsnprintf(heap, (size_t)n + 1, fmt, again) >= 0) {
            text = heap;
            len = (size_t)n;
        } else {
            len = sizeof stack - 1;
        }
    }
    va_end(again);
    h->deliver(env, instance, status, category, text, len);
    free(heap);
}
