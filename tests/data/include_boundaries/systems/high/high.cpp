// Fixture: the system library.
