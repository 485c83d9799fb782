#include "b/b.h"

int a() { return b(); }
