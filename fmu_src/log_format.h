/* A message as an FMI 2.0 logger's format, for status_shim.c and python_bridge.c.
 *
 * The logger's message is a format, as printf's (FMI 2.0 section 2.1.5), and these binaries pass
 * it with no argument: a '%' in the text is doubled so that an importer that formats it shows the
 * text as it is.
 */
#ifndef INERTER_LOG_FORMAT_H
#define INERTER_LOG_FORMAT_H

#include <stdlib.h>

/* `message` with every '%' doubled, in memory the caller frees; NULL when out of memory. */
static char *as_format(const char *message)
{
    size_t n = 0;
    const char *from;
    char *text, *to;

    for (from = message; *from != '\0'; from++)
        n += *from == '%' ? 2 : 1;
    text = malloc(n + 1);
    if (text == NULL)
        return NULL;
    for (from = message, to = text; *from != '\0'; from++) {
        if (*from == '%')
            *to++ = '%';
        *to++ = *from;
    }
    *to = '\0';
    return text;
}

#endif
