namespace fdem { const char* version() { return FDEM_VERSION; } }
