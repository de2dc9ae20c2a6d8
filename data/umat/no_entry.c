/* A shared library without a UMAT entry: rendulic must refuse it with one line (docs/umat.md). */
int not_a_umat(void) { return 0; }
