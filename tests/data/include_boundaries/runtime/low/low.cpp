// Fixture: a runtime file that includes a system's header, through a link (layered.txt): still refused.
#include "systems/high/high.h"
