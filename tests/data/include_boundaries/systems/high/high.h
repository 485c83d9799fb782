// Fixture: a system's header.
#pragma once
