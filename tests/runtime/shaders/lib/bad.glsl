// A compile error on line 4 of this included file.
int bad_value() {
    int y = 1;
    return y +* 2;
}
