/* Formatting into fixed buffers, for every layer of the loader: never a message or path cut short silently. */
#ifndef TEXT_H
#define TEXT_H

#include <stdarg.h>
#include <stddef.h>

/* snprintf that says whether everything fit (1), so that a path cut short is never used. */
int text_fits(char *buffer, size_t size, const char *format, ...) __attribute__((format(printf, 3, 4)));
/* Like snprintf, never fails: a message cut at `size` ends in "...". */
void text_format(char *out, size_t size, const char *format, ...) __attribute__((format(printf, 3, 4)));
void text_vformat(char *out, size_t size, const char *format, va_list args) __attribute__((format(printf, 3, 0)));

/* The offset of the first byte of `text` that is not strict UTF-8 (what CPython's decoder accepts: no
 * overlong forms, no surrogates, nothing above U+10FFFF), or -1 if all of it is.  FMI strings are UTF-8
 * (fmi2TypesPlatform.h, fmi3PlatformTypes.h), and the Python side decodes them as such. */
long text_utf8_error(const char *text);

#endif
