/*
 * The fmi2CallbackLogger handed to every FMU instance.
 *
 * FMI 2.0 declares the logger as a C-variadic, printf-style function. Rust (1.95) can call
 * such a function but cannot define one, so this shim does the formatting in C and passes the
 * finished text to a Rust function.
 *
 * componentEnvironment points to the instance's logging state (a #[repr(C)] Rust struct) whose
 * first two fields are `struct fmi_import_log_header`: the Rust function to deliver to, and the
 * lowest status worth formatting. Messages below it are dropped before vsnprintf runs.
 *
 * Formatting: one vsnprintf into a stack buffer; when the message is longer, a second pass into
 * a heap buffer of the exact size, so nothing is truncated. If even malloc fails, the stack text
 * is delivered with an explicit truncation marker. NULL instance, category or format are
 * tolerated (the Rust side substitutes names), and a format vsnprintf rejects is delivered
 * verbatim rather than dropped.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void (*fmi_import_deliver_fn)(void *env, const char *instance, int status,
                                      const char *category, const char *message, size_t len);

/* Must match the first fields of `LogState` in src/logging.rs. */
struct fmi_import_log_header {
    fmi_import_deliver_fn deliver;
    int threshold;
};

#define STACK_BUFFER 1024

static const char TRUNCATED[] = " [message truncated: out of memory]";

static void fallback(const char *instance, int status, const char *category,
                     const char *message) {
    /* The FMU did not pass our componentEnvironment back: nobody to route to but stderr. */
    fprintf(stderr, "[%s] %s status %d: %s (FMU logged without its componentEnvironment)\n",
            instance ? instance : "?", category ? category : "", status, message);
}

void fmi_import_logger(void *env, const char *instance, int status, const char *category,
                       const char *fmt, ...) {
    const struct fmi_import_log_header *h = (const struct fmi_import_log_header *)env;
    /* Unsigned comparison: a negative (garbage) status is never dropped; Rust maps it to fatal. */
    if (h != NULL && (unsigned)status < (unsigned)h->threshold) {
        return;
    }

    char stack[STACK_BUFFER];
    char *heap = NULL;
    const char *text;
    size_t len;

    if (fmt == NULL) {
        text = "";
        len = 0;
    } else {
        va_list ap;
        va_list again;
        va_start(ap, fmt);
        va_copy(again, ap);
        int n = vsnprintf(stack, sizeof stack, fmt, ap);
        va_end(ap);
        if (n < 0) {
            /* An encoding error: deliver the format itself rather than lose the message. */
            text = fmt;
            len = strlen(fmt);
        } else if ((size_t)n < sizeof stack) {
            text = stack;
            len = (size_t)n;
        } else {
            heap = (char *)malloc((size_t)n + 1);
            if (heap != NULL && vsnprintf(heap, (size_t)n + 1, fmt, again) >= 0) {
                text = heap;
                len = (size_t)n;
            } else {
                size_t keep = sizeof stack - sizeof TRUNCATED;
                memcpy(stack + keep, TRUNCATED, sizeof TRUNCATED);
                text = stack;
                len = keep + sizeof TRUNCATED - 1;
            }
        }
        va_end(again);
    }

    if (h != NULL && h->deliver != NULL) {
        h->deliver(env, instance, status, category, text, len);
    } else {
        fallback(instance, status, category, text);
    }
    free(heap);
}
