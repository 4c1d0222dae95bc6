/* Formatting into fixed buffers (see text.h). */
#include "text.h"

#include <stdio.h>
#include <string.h>

int text_fits(char *buffer, size_t size, const char *format, ...) {
    va_list args;
    va_start(args, format);
    int n = vsnprintf(buffer, size, format, args);
    va_end(args);
    return n >= 0 && (size_t)n < size;
}

void text_vformat(char *out, size_t size, const char *format, va_list args) {
    if (!size) return;
    int n = vsnprintf(out, size, format, args);
    if (n < 0) out[0] = '\0';
    else if ((size_t)n >= size && size > 4) memcpy(out + size - 4, "...", 4);
}

void text_format(char *out, size_t size, const char *format, ...) {
    va_list args;
    va_start(args, format);
    text_vformat(out, size, format, args);
    va_end(args);
}
