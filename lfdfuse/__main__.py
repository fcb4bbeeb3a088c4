from lfdfuse.cli.main import main

main()
