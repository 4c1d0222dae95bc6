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

#endif
