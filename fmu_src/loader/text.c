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

long text_utf8_error(const char *text) {
    const unsigned char *s = (const unsigned char *)text;
    for (long k = 0; s[k];) {
        unsigned char b = s[k];
        int n = b < 0x80 ? 0 : b >= 0xC2 && b <= 0xDF ? 1 : b >= 0xE0 && b <= 0xEF ? 2 : b >= 0xF0 && b <= 0xF4 ? 3 : -1;
        if (n < 0) return k;
        /* the second byte's range rules out overlong forms, surrogates and code points above U+10FFFF */
        unsigned char low = b == 0xE0 ? 0xA0 : b == 0xF0 ? 0x90 : 0x80;
        unsigned char high = b == 0xED ? 0x9F : b == 0xF4 ? 0x8F : 0xBF;
        for (int j = 1; j <= n; j++) {
            unsigned char next = s[k + j];
            if (next < (j == 1 ? low : 0x80) || next > (j == 1 ? high : 0xBF)) return k;
        }
        k += n + 1;
    }
    return -1;
}
