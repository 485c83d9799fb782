#include "b/b.h"

int b() { return 1; }
