from spectracam.cli import main

main()
