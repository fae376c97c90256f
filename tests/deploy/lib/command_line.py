"""Reading a farm command line as deploy/'s files write it (a list of words), for the deploy tests."""


def flag_values(argv, flag):
    """Every value of `flag` in argv, written `--flag=value` or `--flag value`, in order."""
    values = []
    for i, word in enumerate(argv):
        if word.startswith(flag + "="):
            values.append(word[len(flag) + 1:])
        elif word == flag and i + 1 < len(argv):
            values.append(argv[i + 1])
    return values
